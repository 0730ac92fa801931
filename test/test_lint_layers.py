# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Imports run one way, checked on the source of every module (inside functions too).

spatial <- joints <- model <- urdf, algorithms <- backends <- the API <- recordings <- the
commands (check, replay, fleet: side by side) <- ros <- sim <- tools.
"""

import ast
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = os.path.join(ROOT, 'spatial_dynamics')

# Rank of each layer: a module may import modules of its own rank or below, never above.
RANKS = {
    'spatial': 0, 'text': 0, 'files': 0, 'bounds': 0, 'extras': 0, 'joints': 1, 'model': 2,
    'urdf': 3, 'base': 3, 'terms': 3, 'algorithms': 3, 'trajectory': 3, 'wrench': 3, 'effort': 5,
    'identification': 5, 'drives': 5, 'excitation': 5, 'contacts': 5, 'contact_kinematics': 5,
    'contact_qp': 5,
    'backends': 4,
    '': 5,                  # the package itself: the public API (spatial_dynamics/__init__.py)
    'recordings': 6,        # bags read, cleaned, differentiated: the floor of the commands
    'check': 7,             # a command on the library
    'replay': 7,            # recorded data and trajectories against the model (no rclpy)
    'fleet': 7,             # a fleet's bags on a Dask cluster: the recordings, summed fits
    'ros': 8,               # the node and its pure configuration
    'sim': 9,               # the simulated robot: robot.py pure (MuJoCo), node.py on ros/;
    #                         above ros (it reuses the node's readers and spin), below tools
    'tools': 10,            # demo, closed_loop, latency, soak, ...: use everything, used by none
    #                         (the benchmarks live outside the package: benchmarks/)
}
# The commands: side by side on one rank, none imports another's modules. One command may
# run another through that one's entry point, its package alone (``replay fleet`` runs
# ``spatial_dynamics.fleet``: add_arguments, run), never a module inside it. Below the tools
# (which demonstrate the commands), nothing outside a command imports it.
COMMANDS = ('check', 'replay', 'fleet')
# Imports against the direction: none (model.py knows no parser: urdf/ installs
# Model.from_urdf, so the record stays below its reader).
ALLOWED_UPWARD: set = set()
ROS = ('rclpy', 'rcl_interfaces', 'sensor_msgs', 'std_msgs', 'trajectory_msgs', 'geometry_msgs',
       'diagnostic_msgs', 'builtin_interfaces', 'ament_index_python')


def modules():
    """Yield (dotted name inside the package, path) of every module of the package."""
    for dirpath, _, filenames in os.walk(PACKAGE):
        for filename in sorted(filenames):
            if filename.endswith('.py'):
                path = os.path.join(dirpath, filename)
                rel = os.path.relpath(path, PACKAGE)[:-3].replace(os.sep, '.')
                yield ('' if rel == '__init__' else rel.removesuffix('.__init__')), path


def layer(name: str) -> str:
    """Return the layer of a module (its first name inside the package)."""
    return name.split('.')[0]


def imports(name: str, path: str):
    """Yield the absolute module names ``path`` imports, at any depth of its code."""
    is_package = path.endswith('__init__.py')
    with open(path, encoding='utf-8') as f:
        tree = ast.parse(f.read())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                base = node.module
            else:
                parts = ['spatial_dynamics'] + (name.split('.') if name else [])
                parts = parts[:len(parts) - node.level + (1 if is_package else 0)]
                base = '.'.join(parts + ([node.module] if node.module else []))
            yield base
            for alias in node.names:    # `from . import layout` imports a module too
                yield f'{base}.{alias.name}'


def inside(module: str):
    """Return the module's name inside the package, or None for other modules."""
    if module == 'spatial_dynamics':
        return ''
    if module.startswith('spatial_dynamics.'):
        return module[len('spatial_dynamics.'):]
    return None


LAYERS = [(name, path) for name, path in modules() if layer(name) in RANKS]
UNKNOWN = [name for name, _ in modules() if layer(name) not in RANKS]


def test_every_module_has_a_layer():
    assert not UNKNOWN, f'modules outside the layers {sorted(RANKS)}: {UNKNOWN}'


@pytest.mark.parametrize('name,path', LAYERS, ids=[n or '__init__' for n, _ in LAYERS])
def test_imports_run_one_way(name, path):
    here = layer(name)
    wrong = []
    for module in imports(name, path):
        target = inside(module)
        if target is None:
            top = module.split('.')[0]
            if top in ROS and RANKS[here] < RANKS['ros']:
                wrong.append(f'{module} (ROS, below the ros layer)')
            continue
        there = layer(target)
        if there not in RANKS or (here, there) in ALLOWED_UPWARD:
            continue   # an attribute imported from a module (`from .x import name`)
        if RANKS[there] > RANKS[here]:
            wrong.append(f'{module} (layer {there!r} is above {here!r})')
    assert not wrong, f'{name or "spatial_dynamics"} imports: {wrong}'


def module_of(target: str, known) -> str:
    """Return the module ``target`` names: itself, or the module an attribute is taken from."""
    while target not in known and '.' in target:
        target = target.rsplit('.', 1)[0]
    return target


def import_graph() -> dict:
    """Return {module: the modules of the package it imports} (inside functions too).

    A module's own packages are left out: Python imports them before the module itself,
    whatever it writes (``from . import compiled`` names its package only as the place).
    """
    known = {name for name, _ in modules()}
    graph = {}
    for name, path in modules():
        parents = {'.'.join(name.split('.')[:i]) for i in range(len(name.split('.')))}
        edges = set()
        for module in imports(name, path):
            target = inside(module)
            if target is None:
                continue
            target = module_of(target, known)
            if target in known and target != name and target not in parents:
                edges.add(target)
        graph[name] = edges
    return graph


def cycles(graph: dict) -> list:
    """Return the import cycles of ``graph``: its strongly connected parts of two or more.

    Tarjan's algorithm, iterative; each part sorted, the parts sorted.
    """
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, edges = work[-1]
            w = next(edges, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                part = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    part.append(w)
                    if w == v:
                        break
                if len(part) > 1:
                    found.append(sorted(part))
    return sorted(found)


def test_cycles_are_found():
    graph = {'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}, 'e': {'e'}}
    assert cycles(graph) == [['a', 'b', 'c']]
    assert cycles({'a': {'b'}, 'b': set()}) == []


def test_no_module_imports_one_that_imports_it_back():
    """No import cycle between modules, lazy or under TYPE_CHECKING (all are read here).

    A cycle makes the two modules one layer in disguise: neither can be read, tested or
    imported first on its own. The one exception is :data:`ALLOWED_UPWARD` (inside a method).
    """
    graph = import_graph()
    for low_module, high_module in ALLOWED_UPWARD:
        graph[low_module].discard(high_module)
    assert cycles(graph) == []


def command_imports(name: str, path: str):
    """Yield the modules of other commands that ``name`` imports, and the way it names them.

    ``(target, entry)``: ``entry`` when ``target`` is another command's package itself.
    """
    known = {n for n, _ in modules()}
    for module in imports(name, path):
        target = inside(module)
        if target is None or layer(target) not in COMMANDS or layer(target) == layer(name):
            continue
        target = module_of(target, known)
        yield target, target == layer(target)


@pytest.mark.parametrize('name,path', LAYERS, ids=[n or '__init__' for n, _ in LAYERS])
def test_no_command_imports_another_commands_modules(name, path):
    """A command uses another only through its entry point; below the tools, none at all."""
    here = layer(name)
    wrong = []
    for target, entry in command_imports(name, path):
        if here in COMMANDS and not entry:
            wrong.append(f'{target} (a module of the command {layer(target)!r})')
        elif here not in COMMANDS and RANKS[here] < RANKS['tools']:
            wrong.append(f'{target} (the command {layer(target)!r}, from outside the commands)')
    assert not wrong, f'{name or "spatial_dynamics"} imports: {wrong}'


def test_the_command_rule_finds_a_reach_into_another_command(tmp_path):
    """The rule reads ``from ..fleet import command``, not only ``from .. import fleet``."""
    path = tmp_path / 'x.py'
    path.write_text('from ..fleet import command\nfrom .. import fleet\n'
                    'from ..recordings import bags\n')
    found = sorted(set(command_imports('replay.x', str(path))))
    assert found == [('fleet', True), ('fleet.command', False)], found
