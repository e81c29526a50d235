"""Process helpers shared by the command line and the worker pools."""

from __future__ import annotations

import sys


def die_with_parent(signum: int) -> bool:
    """Ask Linux to send this process ``signum`` when its parent dies (``prctl(2)``,
    ``PR_SET_PDEATHSIG``): a benchmark child of ``poc-env bench`` or a pool worker must not
    outlive the command that started it and write its outputs after a kill.

    Returns whether the request was made (False off Linux, or where libc refuses it); the
    caller checks its parent is still there afterwards, as the request does not cover a parent
    that died before it.
    """
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(1, int(signum), 0, 0, 0) == 0  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return False
