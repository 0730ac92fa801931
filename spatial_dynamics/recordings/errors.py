# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Why a recording cannot be used: the refusals every reader and command raises, on one line."""


class Refused(Exception):
    """The input cannot be used; the message says why (exit status 1)."""


class BagError(ValueError):
    """The bag cannot be read as asked: no such bag, topic or type; the message says which."""


def one_line(err: BaseException) -> str:
    """Return an exception's message on one line."""
    return ' '.join(str(err).split()) or type(err).__name__
