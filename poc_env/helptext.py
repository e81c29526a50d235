"""How every ``poc-env`` command's ``--help`` reads: defaults shown, examples that run.

:class:`HelpFormatter` is the formatter of every parser of the command line (the subcommands,
``bench``'s benchmarks, ``experiment``): each option with a default shows it (``(default:
paper_6_2)``), and options whose default is None, a
flag's False or suppressed show nothing (the help says what happens instead). Descriptions and
epilogs keep their line breaks, so :func:`examples` can end a help with command lines.

``tests/e2e/test_help.py`` reads every example back with :func:`help_examples` and parses it
(and runs the cheap ones): an example that no longer parses, or names a scenario key, policy or
task that is gone, fails the suite.
"""

from __future__ import annotations

import argparse
import copy
from collections.abc import Iterable

#: First line of the examples block of an epilog.
EXAMPLES_HEADING = "examples:"
#: The program name every example starts with.
PROG = "poc-env"


def shown_default(action: argparse.Action) -> str | None:
    """The default of ``action`` as its help shows it, or None when none is shown (None,
    ``SUPPRESS``, a flag's ``False``/``True``, an empty list)."""
    default = action.default
    if default is None or default is argparse.SUPPRESS or isinstance(default, bool):
        return None
    if action.help is argparse.SUPPRESS or not action.option_strings:
        return None
    if isinstance(default, (list, tuple)):
        return " ".join(str(d) for d in default) if default else None
    return str(default)


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Raw description and epilog (examples keep their lines), and every option's default at
    the end of its help as ``(default: VALUE)`` (:func:`shown_default`)."""

    def add_argument(self, action: argparse.Action) -> None:
        value = shown_default(action)
        if action.help is None and value is not None:  # argparse would print no help line
            action = copy.copy(action)
            action.help = "(default: " + value.replace("%", "%%") + ")"
        super().add_argument(action)

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        value = shown_default(action)
        if value is None or "%(default)" in text:
            return action.help
        escaped = value.replace("%", "%%")
        shown = f"(default: {escaped})"
        if text in ("", shown):  # no help of its own (add_argument gave it just the default)
            return shown
        return f"{text} {shown}"


def examples(*lines: str) -> str:
    """An epilog of example command lines (each ``poc-env ...``), one per line."""
    if not lines or not all(line.startswith(PROG + " ") for line in lines):
        raise ValueError(f"examples: each a command line starting {PROG!r}: {lines}")
    return EXAMPLES_HEADING + "\n" + "\n".join(f"  {line}" for line in lines)


def help_examples(text: str) -> list[str]:
    """The example command lines of a formatted help: the indented ``poc-env ...`` lines after
    its ``examples:`` line."""
    out: list[str] = []
    inside = False
    for line in text.splitlines():
        if line.strip() == EXAMPLES_HEADING:
            inside = True
        elif inside and line.startswith("  ") and line.strip().startswith(PROG + " "):
            out.append(line.strip())
        elif inside and line.strip():
            inside = False
    return out


def use_everywhere(parsers: Iterable[argparse.ArgumentParser]) -> None:
    """Give every parser of ``parsers`` the :class:`HelpFormatter`."""
    for p in parsers:
        p.formatter_class = HelpFormatter


def walk(parser: argparse.ArgumentParser) -> list[tuple[str, argparse.ArgumentParser]]:
    """``(command path, parser)`` of ``parser`` and every sub-parser below it, depth first
    (``("poc-env", top)``, ``("poc-env plan", ...)``, ``("poc-env scenario import", ...)``)."""
    out = [(parser.prog, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):  # aliases: once
                out += walk(sub)
    return out
