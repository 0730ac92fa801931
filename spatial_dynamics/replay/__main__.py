# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics over a recording: measured effort against the model, and a trajectory check.

    python -m spatial_dynamics.replay residual BAG --urdf URDF [--topic /joint_states]
                                      [--out DIR] [--window 0.05] [--residual csv|npy|none]
                                      [--base-odometry TOPIC | --base-imu TOPIC]
    python -m spatial_dynamics.replay identify BAG --urdf URDF [--threshold 0.01]
                                      [--inertias [LINK ...] | --payload LINK] [--drives]
                                      [--also BAG ...] [--validate BAG]
                                      [--write-urdf OUT.urdf]
    python -m spatial_dynamics.replay trajectory FILE.yaml --urdf URDF [--rate 1000]
    python -m spatial_dynamics.replay trajectory BAG --topic /arm/joint_trajectory --urdf URDF
    python -m spatial_dynamics.replay annotate FILE.yaml --urdf URDF --out OUT.yaml
    python -m spatial_dynamics.replay excite --urdf URDF --duration 30 --out plan.yaml
    ros2 run spatial_dynamics replay ...

A bag (rosbag2, sqlite3 or MCAP; no ROS installation needed) gives q, q̇ and the measured
effort by joint name; q̈ comes from a zero-phase Savitzky-Golay derivative of q̇ (of q when
the bag has no velocities). The model torque is the rigid-body RNEA for the whole bag in one
batched call. Written to DIR: summary.csv (per joint), residual.csv (per sample: t, measured
- model per joint), measured_vs_model.png, residual.png (``residual``). ``identify`` fits
per-joint damping, Coulomb friction (tanh(q̇/threshold), as the node) and armature to the
residual. On a moving base (a mobile manipulator) ``--base-odometry`` or ``--base-imu`` reads
the base's motion from the same bag (:mod:`spatial_dynamics.recordings.base_topics`); it goes
to RNEA and every fit.

``identify --inertias [LINK ...]`` fits the inertial parameters of the links (default all
moving ones; physically consistent, regularised toward the URDF; with ``--drives`` jointly
with the drives) and warns, naming them, about the combinations the recording does not determine;
``--payload LINK`` fits a payload. What was identified is checked on a held-out recording
(``--validate BAG``: the residual with the URDF and with the correction, validation.csv,
identification.png), listed with one σ (parameters.csv), and ``--write-urdf OUT.urdf``
writes the URDF with only the identified ``<inertial>`` and ``<dynamics>`` replaced.

``excite`` plans a motion that determines every base parameter (:mod:`.excite`), for
joint_trajectory_controller to execute while the bag is recorded.

A trajectory (``trajectory`` of a YAML file, or of a bag's ``--topic``) is sampled like
joint_trajectory_controller's splines at ``--rate`` and τ compared with the URDF effort limits;
``annotate`` writes a plan with the effort for joint_trajectory_controller (:mod:`.annotate`).

Exit status: 0 done (samples skipped are listed with the reason), 1 refused (no such bag,
topic or joint, nothing usable, rosbags missing; a trajectory exceeding an effort limit),
2 bad usage, 130 interrupted (Ctrl-C: each file is whole or not there). Every input and
output is checked before any work: an output that is an input, in a bag directory, a
directory, a named pipe or a device is refused; every file is written to a temporary beside
it and renamed.

This module only dispatches: one module a subcommand (:mod:`.residual`, :mod:`.identify`,
:mod:`.trajectory`, :mod:`.annotate`, :mod:`.excite`, :mod:`.fleet`), each declaring its
parser (its ``command``) and running it; what they share of the command line is
:mod:`.arguments`', what they check before any work :mod:`.paths`'.
"""

from __future__ import annotations

import argparse
import sys
from typing import Optional, Sequence

from ..extras import install_hint
from . import annotate, excite, fleet, identify, residual, trajectory
from .arguments import EXIT_STATUS, Parser

#: The subcommands, in the order of ``replay --help``: each a function of the subparsers.
COMMANDS = (residual.command, identify.command, trajectory.command, annotate.command,
            excite.command, fleet.command)


def parser() -> argparse.ArgumentParser:
    """Return the command's argument parser: one subparser a job (:data:`COMMANDS`)."""
    p = Parser(prog='replay', description=__doc__.split('\n\n')[0],
               formatter_class=argparse.RawDescriptionHelpFormatter,
               epilog='Each command has its --help. ' + EXIT_STATUS)
    sub = p.add_subparsers(dest='command', required=True, title='commands')
    for command in COMMANDS:
        command(sub)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status (0, 1, 2 or 130)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser().parse_args(argv)
    try:
        return args.run(args)
    except ImportError as err:        # an optional dependency: say which extra brings it
        hint = install_hint(err, 'fleet' if args.command == 'fleet' else 'replay')
        if not hint:
            raise
        print(f'error: replay {args.command}: {hint}', file=sys.stderr)
        return 1


if __name__ == '__main__':
    sys.exit(main())
