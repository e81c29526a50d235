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
import re
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

_UNSAFE_IN_NAME = re.compile(r"[^A-Za-z0-9._+-]+")


def safe_stem(text: str, limit: int = 64) -> str:
    """``text`` made safe as one component of a file name that the program chooses (a run
    folder named after a scenario): every run of characters outside ``[A-Za-z0-9._+-]``
    becomes ``_`` (path separators, ``..``, control characters, spaces included), leading
    dots go, and the result is at most ``limit`` characters (``_`` when nothing is left).

    >>> safe_stem("../../../etc/x")
    '__.__._etc_x'
    >>> safe_stem("Harbin search, day 2")
    'Harbin_search_day_2'
    """
    stem = _UNSAFE_IN_NAME.sub("_", str(text)).lstrip(".")
    stem = stem.replace("..", "_.")  # no parent reference survives anywhere in the name
    return stem[:limit] or "_"


def check_replaceable(path: str | os.PathLike[str], field: str = "output") -> None:
    """Refuse to replace anything but a regular file: an atomic write renames its temporary
    file over ``path``, which would swap a device (``/dev/null``), a FIFO or a socket for a
    plain file (as root, for everyone on the machine). A new path, or a regular file (through
    symbolic links), passes.

    Raises
    ------
    ConfigError
        ``path`` exists and is not a regular file.
    """
    import stat

    from poc_env.errors import ConfigError

    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as err:  # a path poc-env cannot even look at
        raise ConfigError(field, os.fspath(path), f"a path poc-env can write ({err})") from None
    if stat.S_ISREG(mode):
        return
    raise ConfigError(
        field, os.fspath(path), f"a new path or a regular file to replace; it is {_kind(mode)}"
    )


def _kind(mode: int) -> str:
    """What a path that is not a regular file is, from its ``st_mode``."""
    import stat

    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"),
             (stat.S_ISSOCK, "a socket"))  # fmt: skip
    return next((k for test, k in kinds if test(mode)), "not a regular file")


def check_input_file(
    field: str, path: str | os.PathLike[str], allowed: str, *, strict: bool = True
) -> None:
    """Refuse an input ``path`` that cannot be read as a file, before anything reads it, naming
    ``field`` (the option it came from), the path and why, after ``allowed``: missing, a folder
    or another file that is not a regular one (a FIFO or a device: a read would block, or never
    end), or unreadable (no permission: said so, not called empty). An empty file passes (what
    is empty is the reader's to say). ``strict=False``: a value that may also be a name (a
    built-in scenario, a run folder) -- a missing path or a folder passes, to the command.

    Raises
    ------
    ConfigError
    """
    import stat

    from poc_env.errors import ConfigError

    text = os.fspath(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        if not strict:
            return
        raise ConfigError(field, text, f"{allowed}; it does not exist") from None
    except OSError as err:
        raise ConfigError(field, text, f"{allowed}; unreadable ({err.strerror})") from None
    if stat.S_ISDIR(mode) and not strict:
        return
    if not stat.S_ISREG(mode):
        raise ConfigError(field, text, f"{allowed}; it is {_kind(mode)}, not a regular file")
    try:
        os.close(os.open(path, os.O_RDONLY))
    except OSError as err:
        raise ConfigError(field, text, f"{allowed}; unreadable ({err.strerror})") from None


def publish_atomic(tmp: str | os.PathLike[str], path: str | os.PathLike[str]) -> None:
    """Give a finished temporary file the usual permissions and rename it over ``path``
    (never over anything but a regular file: :func:`check_replaceable`)."""
    check_replaceable(path)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def _staging_folder(path: Path) -> tuple[list[Path], Path]:
    """The folders above ``path`` that do not exist yet (deepest first) and the nearest one
    that does: an atomic write stages there (the same file system as the folders it makes
    when it publishes), so a failure or a kill before then leaves no new folder behind."""
    missing = [q for q in (path.parent, *path.parent.parents) if not q.is_dir()]
    return missing, (missing[-1].parent if missing else path.parent)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; publish it over ``path`` if the block succeeds.

    ``suffix`` keeps an extension that writers infer the format from (``".png"``, ``".zip"``).
    The temporary file waits in the nearest existing folder of ``path`` (the same file system
    as the folders to be made under it); the destination's missing folders are made only when
    it is published, so a failure or a kill before then leaves no empty folders behind. On an
    exception the temporary file is deleted and the exception propagates. The temporary file
    is named ``.NAME.tmp-PID-XXXX``: one left by a killed process (its PID gone) is removed by
    the next atomic write staged in the same folder.
    """
    p = Path(path)
    check_replaceable(p)  # before any work: never a device, FIFO or socket
    missing, staging = _staging_folder(p)
    clean_stale_temp_files(staging)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}{_TEMP}{os.getpid()}-", suffix=suffix, dir=staging)
    os.close(fd)
    published = False
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as fh:  # on disk before the rename, so a crash leaves old or new
            os.fsync(fh.fileno())
        p.parent.mkdir(parents=True, exist_ok=True)
        publish_atomic(tmp, p)
        published = True
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if not published:
            for folder in missing:  # made by this call (a refused publish), deepest first
                with contextlib.suppress(OSError):
                    folder.rmdir()


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return ``path``."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically and return ``path``."""
    return write_bytes_atomic(path, text.encode("utf-8"))


#: Marker of an atomic write's temporary file: ``.NAME.tmp-PID-XXXX``.
_TEMP = ".tmp-"
#: Prefix of a command's staging folder beside its output folder: ``.NAME.partial-PID-XXXX``.
_STAGING = ".partial-"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


def clean_stale_temp_files(folder: Path) -> None:
    """Remove the temporary files of :func:`atomic_path` in ``folder`` whose process is gone
    (left by a kill between creating and publishing them)."""
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for e in entries:
        if not e.name.startswith(".") or _TEMP not in e.name:
            continue
        pid = e.name.rsplit(_TEMP, 1)[1].split("-", 1)[0]
        if pid.isdigit() and not _pid_alive(int(pid)) and e.is_file(follow_symlinks=False):
            with contextlib.suppress(OSError):
                os.unlink(e.path)


def _clean_stale_staging(dest: Path, where: Path) -> None:
    """Tidy up after runs into ``dest`` that were killed (their PID is gone): a merge killed
    half-way is rolled back (:func:`_roll_back`: ``dest`` as it was before that run), then
    their staging folders in the folder ``where`` are removed."""
    import shutil

    try:
        siblings = sorted(where.iterdir())
    except OSError:
        return
    for kind in (_ASIDE, _STAGING):  # the roll-back first: it reads nothing from the staging
        prefix = f".{dest.name}{kind}"
        for p in siblings:
            if not p.name.startswith(prefix) or not p.is_dir() or p.is_symlink():
                continue
            pid = p.name[len(prefix) :].split("-", 1)[0]
            if not pid.isdigit() or _pid_alive(int(pid)):
                continue
            if kind == _STAGING:
                shutil.rmtree(p, ignore_errors=True)
            elif (p / _JOURNAL).is_file() and dest.is_dir():
                _roll_back(p, dest)
            else:  # killed before its journal was written: nothing had moved
                shutil.rmtree(p, ignore_errors=True)


def _check_merge(src: Path, dest: Path, field: str = "output") -> None:
    """Before :func:`_merge_into` moves anything: every file it would replace is a regular
    file (:func:`check_replaceable`: a folder of the user's in the way is refused, never
    deleted), and a folder it writes goes into a folder or a new path, so a merge is whole or
    not started."""
    from poc_env.errors import ConfigError

    for entry in src.iterdir():
        target = dest / entry.name
        if entry.is_dir() and not entry.is_symlink():
            if target.is_dir():
                _check_merge(entry, target, field)
            elif os.path.lexists(target):
                raise ConfigError(
                    field, os.fspath(target), "a new path or a folder to write a folder into; "
                    "it is a file",
                )  # fmt: skip
        else:
            check_replaceable(target, field)


def _merges(src: Path, dest: Path) -> list[tuple[Path, Path]]:
    """The renames that put ``src``'s files into ``dest``: (staged entry, target) pairs, a
    staged folder whose namesake is a folder merged file by file, any other entry moved whole
    (checked first by :func:`_check_merge`: only regular files are replaced)."""
    moves = []
    for entry in sorted(src.iterdir()):
        target = dest / entry.name
        if entry.is_dir() and not entry.is_symlink() and target.is_dir():
            moves += _merges(entry, target)
        else:
            moves.append((entry, target))
    return moves


#: Prefix of the folder where a merge keeps the files it replaces until it has published them
#: all: ``.NAME.old-PID-XXXX`` beside the staging folder.
_ASIDE = ".old-"
#: The journal in that folder: every target of the merge, with the name its old file was
#: moved to (``null``: the target was new), written before anything moves.
_JOURNAL = "journal.json"


def _roll_back(aside: Path, dest: Path, moved: int | None = None) -> None:
    """Undo a merge into ``dest`` from its folder ``aside`` (:func:`_merge_into`): every new
    file or folder it put in place is removed, every old file goes back. ``moved``: the number
    of journal entries this process reached (``None``: a killed run's, all entries checked)."""
    import json
    import shutil

    entries = json.loads((aside / _JOURNAL).read_text("utf-8"))
    for rel, saved in reversed(entries[:moved] if moved is not None else entries):
        target = dest / rel
        if saved is None or (aside / saved).exists() or (aside / saved).is_symlink():
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            elif os.path.lexists(target):
                os.unlink(target)
        if saved is not None and os.path.lexists(aside / saved):
            os.replace(aside / saved, target)
    shutil.rmtree(aside)


def _merge_into(src: Path, dest: Path, where: Path) -> None:
    """Move every file of ``src`` into ``dest`` (same file system), all or none.

    The files it replaces are first moved aside, one rename each, into a folder
    ``.NAME.old-PID-XXXX`` in ``where`` (beside the staging folder), with a journal of every
    move written before the first; only when every new file is in place is that folder
    removed. An error or a Ctrl-C in between puts the old files back and removes the new ones
    (:func:`_roll_back`); a run killed in between leaves the folder, and the next run into
    ``dest`` rolls it back first (:func:`_clean_stale_staging`). POSIX has no rename of many
    files at once, so another process looking at ``dest`` during the merge can see it half
    done; no outcome leaves it so.
    """
    import json
    import shutil

    moves = _merges(src, dest)
    aside = Path(tempfile.mkdtemp(prefix=f".{dest.name}{_ASIDE}{os.getpid()}-", dir=where))
    journal = [
        (os.path.relpath(target, dest), str(k) if os.path.lexists(target) else None)
        for k, (_, target) in enumerate(moves)
    ]
    write_text_atomic(aside / _JOURNAL, json.dumps(journal))
    reached = 0
    try:
        for k, ((entry, target), (_, saved)) in enumerate(zip(moves, journal, strict=True)):
            reached = k + 1
            if saved is not None:
                os.replace(target, aside / saved)
            os.replace(entry, target)
    except BaseException:
        _roll_back(aside, dest, reached)
        raise
    shutil.rmtree(aside, ignore_errors=True)


def check_out(
    field: str, value: str | os.PathLike[str] | None, kind: str, suffix: str | None = None
) -> None:
    """Check an output path before any work: ``kind`` is ``"file"`` or ``"folder"``;
    ``suffix`` (a file's, e.g. ``".png"``): the one its format needs.

    Refused: an empty path, a file where a folder is expected (or the reverse), a path under a
    file, a file not ending in ``suffix`` (case ignored), and a path whose nearest existing
    folder poc-env cannot write into (tried by creating and removing a temporary folder there).
    """
    from poc_env.errors import ConfigError

    if value is None:
        return
    text = os.fspath(value)
    what = "a file path (not a folder)" if kind == "file" else "a folder path (not a file)"
    allowed = f"{what} that poc-env can create or write"
    if not text or "\0" in text:
        raise ConfigError(field, text, allowed)
    if suffix is not None and not text.lower().endswith(suffix):
        raise ConfigError(field, text, f"a path ending in {suffix} (the file is written in "
                          "that format whatever its name)")  # fmt: skip
    path = Path(text)
    try:
        if kind == "file":
            if path.is_dir() or text.endswith(("/", os.sep)):
                raise ConfigError(field, text, f"{what}; it is a folder")
            check_replaceable(path, field)  # /dev/null, a FIFO: never swapped for a file
            start = path.parent
        else:
            if path.exists() and not path.is_dir():
                raise ConfigError(field, text, f"{what}; it is an existing file")
            start = path
        nearest = start
        while not nearest.exists() and nearest != nearest.parent:
            nearest = nearest.parent
        if not nearest.is_dir():
            raise ConfigError(field, text, f"{what}; {nearest} is a file, not a folder")
        probe = tempfile.mkdtemp(prefix=".poc-env-probe-", dir=nearest)
        os.rmdir(probe)
    except OSError as err:
        raise ConfigError(field, text, f"{allowed} ({err.strerror})") from None


def _same_path(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """``a`` and ``b`` name the same file: the same inode when both exist (hard and symbolic
    links included), else the same absolute path once resolved."""
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
        return Path(a).resolve() == Path(b).resolve()
    except (OSError, ValueError):  # a path the system refuses: its own check reports it
        return False


def check_distinct(
    outputs: Mapping[str, str | os.PathLike[str] | list | None],
    inputs: Mapping[str, str | os.PathLike[str] | list | None],
) -> None:
    """Refuse an output file that is one of the command's inputs, or another of its outputs,
    before any work: ``plan --out P --plot P`` kept only the last one written, and ``--out``
    naming the scenario YAML or the previous sortie's plan.json replaced the user's file.

    ``outputs``: option -> file path or list of the files it writes (None: not given);
    ``inputs``: option -> path or list of paths (a value that is not an existing file, such as
    a built-in scenario name, is skipped).

    Raises
    ------
    ConfigError
        Naming the output option, its path, and the option it collides with.
    """
    from poc_env.errors import ConfigError

    given = [
        (f, one)
        for f, v in outputs.items()
        if v is not None
        for one in (v if isinstance(v, list) else [v])
    ]
    for k, (field, path) in enumerate(given):
        for other, theirs in given[:k]:
            if other != field and _same_path(path, theirs):
                option = "--" + other.replace("_", "-")
                raise ConfigError(field, os.fspath(path), f"a path other than {option}'s "
                                  "(both would be written to one file)")  # fmt: skip
        for name, value in inputs.items():
            values = value if isinstance(value, list) else [value]
            for v in values:
                if v is not None and os.path.isfile(v) and _same_path(path, v):
                    option = "--" + name.replace("_", "-")
                    raise ConfigError(
                        field, os.fspath(path), f"a path other than the input {option} "
                        f"{os.fspath(v)} (writing it would replace that file)",
                    )  # fmt: skip


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike[str], field: str = "output") -> Iterator[Path]:
    """Yield a staging folder beside ``path``; put its files in place if the block succeeds.

    A command writes its whole output into the staging folder (a hidden sibling
    ``.NAME.partial-PID-XXXX`` on the same file system; in the nearest existing folder above
    ``path`` when its parent does not exist yet, which is made only at the end), so a kill or
    an error during the run leaves the destination as it was, and no new folder. When the
    block succeeds:

    * ``path`` absent or an empty folder: the staging folder is renamed to ``path`` -- the
      output appears complete, in one step, or not at all;
    * ``path`` an existing folder with files (a previous run, or a folder the user keeps other
      files in, such as ``--out .``): the new files replace their namesakes at the very end,
      all or none (:func:`_merge_into`: the old ones moved aside first, put back on a failure,
      and by the next run after a kill); files the command does not write are left alone.

    On an exception the staging folder is removed and the exception propagates. Staging
    folders of killed runs (whose process is gone) are removed by the next run into ``path``.
    A merge refused at the end (a file where a folder goes, a device or a folder where a file
    goes) is a :class:`~poc_env.errors.ConfigError` naming ``field`` (the user's option).
    """
    import shutil

    dest = Path(path)
    if dest.is_symlink() and dest.is_dir():  # stage beside the real folder (same file system)
        dest = dest.resolve()
    created, staging = _staging_folder(dest)  # dest's folders made at the end, if ever
    _clean_stale_staging(dest, staging)
    stage = Path(tempfile.mkdtemp(prefix=f".{dest.name}{_STAGING}{os.getpid()}-", dir=staging))
    done = False
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(stage, 0o777 & ~umask)  # mkdtemp makes it 0o700; a plain mkdir would not
        yield stage
        if dest.is_dir() and not dest.is_symlink() and not any(dest.iterdir()):
            dest.rmdir()
        if not dest.exists():
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.rename(stage, dest)
        else:
            _check_merge(stage, dest, field)
            _merge_into(stage, dest, staging)
        done = True
    finally:
        if stage.exists():
            shutil.rmtree(stage, ignore_errors=True)
        if not done:  # a failed command leaves no folders behind either
            for folder in created:  # deepest first
                with contextlib.suppress(OSError):
                    folder.rmdir()


def csv_text(rows: list[dict]) -> str:
    """Rows (one mapping each) as CSV text, the first row's keys as the header."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


# --------------------------------------------------------------------------- reading JSON
#: Deepest nesting of arrays and objects :func:`loads_json` accepts: every JSON file poc-env
#: reads is a few levels deep; Python's parser recurses once per level and ends in a
#: RecursionError (a traceback) near 1,000.
MAX_JSON_DEPTH = 64
_JSON_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)


def json_depth(text: str | bytes) -> int:
    """The deepest nesting of ``[`` and ``{`` in JSON ``text`` (brackets inside strings not
    counted), without recursion: a vectorised scan, linear in the text.

    >>> json_depth('{"a": [1, {"b": "[[["}]}')
    3
    """
    import numpy as np

    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else bytes(text)
    data = _JSON_STRING.sub(b'""', data)
    b = np.frombuffer(data, dtype=np.uint8)
    step = np.zeros(len(b), dtype=np.int64)
    step[(b == ord("[")) | (b == ord("{"))] = 1
    step[(b == ord("]")) | (b == ord("}"))] = -1
    return int(np.cumsum(step).max(initial=0))


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON (only finite numbers are)")


def loads_json(text: str | bytes, field: str, value: object = None) -> Any:
    """The JSON document ``text``, or a :class:`~poc_env.errors.ConfigError` naming ``field``
    (and ``value``, default the text's start): malformed JSON, nesting deeper than
    :data:`MAX_JSON_DEPTH`, and the non-standard constants ``NaN``, ``Infinity`` and
    ``-Infinity`` that Python's parser takes by default are refused -- never a traceback.

    >>> loads_json('{"a": [1, 2]}', "config")
    {'a': [1, 2]}
    >>> try:
    ...     loads_json("[" * 100 + "]" * 100, "config")
    ... except ValueError as err:
    ...     print(err.allowed)
    JSON nested at most 64 levels deep (this is 100)
    """
    import json

    from poc_env.errors import ConfigError

    shown = value if value is not None else _start(text)
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise ConfigError(
            field, shown, f"JSON nested at most {MAX_JSON_DEPTH} levels deep (this is {depth})"
        )
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as err:  # JSONDecodeError and UnicodeDecodeError too
        raise ConfigError(field, shown, f"a valid JSON document ({err})") from None


def read_bytes(path: str | os.PathLike[str], field: str, what: str) -> bytes:
    """The bytes of the file ``path``; one that cannot be read (missing, a folder, no
    permission) is a :class:`~poc_env.errors.ConfigError` naming ``field``, the path and
    ``what`` is allowed (with the system's reason), never a traceback."""
    from poc_env.errors import ConfigError

    try:
        return Path(path).read_bytes()
    except OSError as err:
        raise ConfigError(field, os.fspath(path), f"{what} ({err.strerror})") from None


def read_text(path: str | os.PathLike[str], field: str, what: str) -> str:
    """The UTF-8 text of the file ``path`` (:func:`read_bytes`'s refusals; text that is not
    UTF-8 is refused too, naming ``field``)."""
    from poc_env.errors import ConfigError

    data = read_bytes(path, field, what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(field, os.fspath(path), f"{what} in UTF-8 ({err.reason})") from None


def read_json(path: str | os.PathLike[str], field: str) -> Any:
    """The JSON document in the file ``path`` (:func:`loads_json`'s rules); a file that cannot
    be read is a :class:`~poc_env.errors.ConfigError` naming ``field`` and the path too."""
    data = read_bytes(path, field, "a readable JSON file")
    return loads_json(data, field, os.fspath(path))


def _start(text: str | bytes, n: int = 30) -> str:
    s = text.decode("utf-8", "replace") if isinstance(text, bytes) else text
    return s[:n] + ("..." if len(s) > n else "")
