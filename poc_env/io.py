"""Atomic file output: every file poc-env writes appears complete or not at all.

A writer fills a temporary file in the destination folder (same file system, so the final
``os.replace`` is atomic), gives it the permissions a plain ``open()`` would have, and renames it
over the destination. If anything fails in between, the temporary file is removed and the old
destination, if any, is untouched. The data is flushed to disk before the rename, so a crash
or ``kill -9`` leaves either the old file or the new one.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path


def publish_atomic(tmp: str | os.PathLike[str], path: str | os.PathLike[str]) -> None:
    """Give a finished temporary file the usual permissions and rename it over ``path``."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; publish it over ``path`` if the block succeeds.

    ``suffix`` keeps an extension that writers infer the format from (``".png"``, ``".zip"``).
    Creates the destination folder. On an exception the temporary file is deleted and the
    exception propagates.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=suffix, dir=p.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as fh:  # on disk before the rename, so a crash leaves old or new
            os.fsync(fh.fileno())
        publish_atomic(tmp, p)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return ``path``."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically and return ``path``."""
    return write_bytes_atomic(path, text.encode("utf-8"))
