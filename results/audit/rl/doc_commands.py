"""Every ``poc-env ...`` command written in the docs and the README, parsed (never run).

Audit i28-audit: ``tests/e2e/test_help.py`` parses the ``--help`` examples; this does the
same for the commands in the shell blocks of docs/*.md and README.md (backslash
continuations joined; inline code in prose is left out, its mentions are fragments), with the
names they give handed to their loaders (tasks, policies, scenarios), so a stale option or id
shows. Commands with placeholders (``NAME``, ``a|b``, ``[...]``, ``<...>``, ``RUN_DIR``) are
skipped. Usage, from the repository root:
``OMP_NUM_THREADS=1 .venv/bin/python results/audit/rl/doc_commands.py``.
"""

from __future__ import annotations

import contextlib
import glob
import importlib
import io
import re
import shlex
import sys

sys.path.insert(0, "tests/e2e")
import test_help as th  # (its _check_names and BENCHMARKS)

from poc_env.agents.rl.args import parse_train_args
from poc_env.cli import parse_command_line

PLACEHOLDER = re.compile(r"\[|\.\.\.|<|RUN_DIR|\bID\b|HEAD|ADDRESS|\bRUN\b|\$\{?[A-Z]")


def commands() -> list[tuple[str, str]]:
    """``(file, command)`` for every poc-env command in a shell block (a fence without a
    language or ``bash``/``sh``/``console``) of the docs and the README."""
    out = []
    for f in [*sorted(glob.glob("docs/*.md")), "README.md"]:
        with open(f, encoding="utf-8") as fh:
            text = fh.read()
        blocks, shell, body = [], False, None
        for line in text.splitlines():
            if line.lstrip().startswith("```"):
                if body is None:  # an opening fence
                    body, shell = [], line.strip()[3:] in ("", "bash", "sh", "console")
                else:  # the closing one
                    if shell:
                        blocks.append("\n".join(body))
                    body = None
            elif body is not None:
                body.append(line)
        for block in blocks:
            for line in re.sub(r"\\\n\s*", " ", block).splitlines():
                line = line.strip().removeprefix("$ ")
                if "poc-env " not in line:
                    continue
                cmd = line[line.index("poc-env ") :]
                for cut in (" #", " > ", " | ", " && "):
                    cmd = cmd.split(cut)[0]
                out.append((f, cmd))
    return out


def check(cmd: str) -> None:
    """Parse ``cmd`` as the CLI would and hand its names to their loaders."""
    ns = parse_command_line(shlex.split(cmd)[1:])
    if ns.command == "train":
        th._check_names(parse_train_args(ns.train_options))
        return
    th._check_names(ns)
    if ns.command == "bench":
        bench = importlib.import_module(th.BENCHMARKS[ns.what]).build_parser().parse_args(ns.rest)
        if ns.what == "suite":
            bench.scenario = None
        th._check_names(bench)


def main() -> int:
    """Print each command that fails to parse or names what does not exist."""
    found = commands()
    bad = 0
    for f, cmd in found:
        if PLACEHOLDER.search(cmd):
            continue
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                check(cmd)
        except SystemExit:
            bad += 1
            print(f"FAIL {f}: {cmd[:160]}\n    {err.getvalue().strip()[-300:]}")
        except Exception as e:
            bad += 1
            print(f"FAIL {f}: {cmd[:160]}\n    {type(e).__name__}: {str(e)[:300]}")
    print(len(found), "commands,", bad, "fail")
    return 0


if __name__ == "__main__":
    sys.exit(main())
