"""Speed and quality benchmarks run by ``poc-env bench NAME`` (one module per benchmark)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any


def write_table_set(
    out: str | Path,
    stem: str,
    rows: list[dict[str, Any]],
    markdown: str,
    figure: Callable[[Path], Any] | None = None,
) -> None:
    """``<stem>.csv`` (the rows), ``<stem>.md`` and, with ``figure``, ``<stem>.png`` (drawn by
    ``figure(path)``) in ``out`` as one set: staged, then merged into ``out``, so a failure
    leaves none of them half-written (:func:`poc_env.io.atomic_dir`)."""
    from poc_env.io import atomic_dir, csv_text, write_text_atomic

    with atomic_dir(Path(out)) as stage:
        write_text_atomic(stage / f"{stem}.csv", csv_text(rows))
        write_text_atomic(stage / f"{stem}.md", markdown)
        if figure is not None:
            figure(stage / f"{stem}.png")


def check_counts(args: Any, **least: int) -> None:
    """Raise :class:`~poc_env.errors.ConfigError` naming the first option of ``least``
    (attribute name = its least value) whose value, or one of whose values (a list option), is
    not an integer that large; an option left at ``None`` (its default) is not checked.

    Called on a benchmark's parsed arguments before any work: a count of runs, seeds or envs
    below one ended in a traceback (``no median for empty data``) or a table of ``nan``.
    """
    from poc_env.errors import as_int

    for name, lo in least.items():
        value = getattr(args, name)
        for v in value if isinstance(value, list) else [value]:
            if v is not None:
                as_int(name, v, lo)


def run_main(main: Callable[[], Any]) -> None:
    """A benchmark module's ``__main__``: bad input ends as ``error: FIELD: ...`` on stderr
    with exit status 2, never a traceback."""
    from poc_env.errors import PocEnvError

    try:
        main()
    except PocEnvError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
