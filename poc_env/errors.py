"""Error types of poc-env.

Every error raised for bad input names the field, the value and what is allowed, so that a
user can fix a YAML file or a call without reading a traceback from deep inside numpy.
"""

from __future__ import annotations

import math
import re
from typing import Any


class PocEnvError(Exception):
    """Base class of every error poc-env raises on purpose."""


class ConfigError(PocEnvError, ValueError):
    """A configuration value (YAML key, keyword override or argument) is not allowed.

    Parameters
    ----------
    field:
        Dotted name of the offending field, e.g. ``"uav.search_speed_kmh"``.
    value:
        The value that was given.
    allowed:
        Plain-language description of what is allowed, e.g. ``"a number > 0"``.
    """

    def __init__(self, field: str, value: Any, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        shown = repr(value)
        if len(shown) > 120:
            shown = shown[:117] + "..."
        super().__init__(f"{field}: got {shown}; allowed: {allowed}")

    def __reduce__(self):
        # rebuilt from its three fields, so it survives pickling (process pools)
        return (type(self), (self.field, self.value, self.allowed))

    def with_prefix(self, prefix: str) -> ConfigError:
        """The same error with ``prefix.`` put in front of the field name."""
        name = f"{prefix}.{self.field}" if prefix else self.field
        return ConfigError(name, self.value, self.allowed)


class MissingExtraError(PocEnvError, ImportError):
    """A feature needs an optional dependency group (``pip install 'poc-env[EXTRA]'``).

    Parameters
    ----------
    extra:
        The extra that provides it: ``"rl"`` (torch, stable-baselines3, tensorboard) or
        ``"plot"`` (matplotlib, pillow).
    what:
        The feature, e.g. ``"poc-env train"``.
    """

    def __init__(self, extra: str, what: str) -> None:
        self.extra = extra
        self.what = what
        super().__init__(f"{what} needs the '{extra}' extra: pip install 'poc-env[{extra}]'")

    def __reduce__(self):
        return (type(self), (self.extra, self.what))


#: the modules of each optional dependency group that a feature checks before it starts
EXTRA_MODULES = {
    "plot": ("matplotlib", "PIL"),
    "rl": ("torch", "stable_baselines3"),
    "ocean": ("xarray", "h5netcdf"),
}


def say_warning(text: Any, file: Any = None) -> None:
    """A warning for the user, one line ``warning: <text>`` on stderr (``file``: another
    stream): the one channel every command's warnings take, those it prints and those raised
    through :mod:`warnings` (the command line's ``showwarning``), so ``poc-env export ... >
    log`` keeps the files' list on stdout and the warnings apart (i24-missionfix)."""
    import sys

    print(f"warning: {text}", file=sys.stderr if file is None else file)


def has_extra(extra: str) -> bool:
    """True when every module of the optional group ``extra`` (:data:`EXTRA_MODULES`) can be
    imported (checked without importing it)."""
    import importlib.util

    return all(importlib.util.find_spec(m) is not None for m in EXTRA_MODULES[extra])


def require_extra(extra: str, what: str, *modules: str) -> None:
    """Raise :class:`MissingExtraError` unless every module in ``modules`` can be imported."""
    import importlib.util

    for m in modules:
        if importlib.util.find_spec(m) is None:
            raise MissingExtraError(extra, what)


def skipped_for_extra(extra: str, what: str) -> str:
    """The note a command prints when it leaves out ``what`` (a figure) for a missing extra."""
    return f"note: no {what}: it needs the '{extra}' extra (pip install 'poc-env[{extra}]')"


class MapFileError(PocEnvError, ValueError):
    """A probability-map file is missing, unreadable or holds an invalid map."""


class GeometryError(PocEnvError, ValueError):
    """A polygon, circle or rectangle is degenerate, self-intersecting or out of range."""


# --------------------------------------------------------------------------- the one coercion
# Every external number, integer and flag (YAML, overrides, keyword arguments, plan.json, region
# files, CLI values) goes through these three functions, so the same input is accepted or refused
# the same way everywhere: numpy scalars count as the numbers they hold; strings, bools (as
# numbers), complex values and None are refused; integers accept integral floats (3.0 -> 3).

#: The largest magnitude an integer input may have (a float holds every integer up to 2^53
#: exactly; larger ones would silently round or overflow a C integer).
MAX_INT = 2**53


def _kind(value: Any) -> str:
    if isinstance(value, str):
        return "a string (write the number without quotes)"
    if isinstance(value, bool):
        return "a true/false flag"
    if value is None:
        return "null (a missing value)"
    return f"a {type(value).__name__}"


def describe_range(lo: float | None, hi: float | None, *, lo_open: bool = False) -> str:
    """``"a number in [lo, hi]"`` and its one-sided forms, as error messages say it."""
    if lo is None and hi is None:
        return "a finite number"
    if hi is None:
        return f"a number {'>' if lo_open else '>='} {lo:g}"
    if lo is None:
        return f"a number <= {hi:g}"
    return f"a number in {'(' if lo_open else '['}{lo:g}, {hi:g}]"


def as_number(
    field: str,
    value: Any,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    allowed: str | None = None,
) -> float:
    """``value`` as a finite float in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``), else
    :class:`ConfigError` naming ``field``, the value and what is allowed."""
    if allowed is None:
        allowed = describe_range(lo, hi, lo_open=lo_open)
    if hasattr(value, "item") and getattr(value, "shape", None) == ():  # numpy scalars, 0-d
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(field, value, f"{allowed}, not {_kind(value)}")
    try:
        x = float(value)
    except OverflowError:  # an int beyond the float range
        raise ConfigError(field, value, allowed) from None
    if not math.isfinite(x):
        raise ConfigError(field, value, allowed + (" (finite)" if "finite" not in allowed else ""))
    if (lo is not None and (x < lo or (lo_open and x == lo))) or (hi is not None and x > hi):
        raise ConfigError(field, value, allowed)
    return x


def as_int(field: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int in ``[lo, hi]``; integral floats (``3.0``) and numpy integers are
    accepted, fractions, NaN, infinities, strings and bools refused."""
    lo_ = -MAX_INT if lo is None else lo
    hi_ = MAX_INT if hi is None else min(hi, MAX_INT)
    allowed = (
        f"an integer >= {lo_}" if hi is None and lo is not None else f"an integer in [{lo_}, {hi_}]"
    )
    if hasattr(value, "item") and getattr(value, "shape", None) == ():
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(field, value, f"{allowed}, not {_kind(value)}")
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        raise ConfigError(field, value, allowed)
    v = int(value)
    if not lo_ <= v <= hi_:
        raise ConfigError(field, value, allowed)
    return v


def as_bool(field: str, value: Any) -> bool:
    """``value`` if it is a true/false flag (numpy bools included); ``"no"``, 0 or 1 refused."""
    if hasattr(value, "item") and getattr(value, "shape", None) == ():
        value = value.item()
    if not isinstance(value, bool):
        raise ConfigError(field, value, "true or false")
    return value


def check_positive(field: str, value: Any, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a float if it is a finite number > 0 (>= 0 with ``allow_zero``)."""
    return as_number(field, value, 0.0, None, lo_open=not allow_zero)


def check_range(field: str, value: Any, lo: float, hi: float) -> float:
    """Return ``value`` as a float if it is a finite number in ``[lo, hi]``."""
    return as_number(field, value, lo, hi)


#: Characters no text that reaches an export may hold: the C0 controls XML 1.0 forbids (all
#: below U+0020 but tab, line feed and carriage return), U+FFFE, U+FFFF and lone UTF-16
#: surrogates (no UTF-8 encoding exists for them). Every export format writes plan text into
#: XML, HTML, JSON or file names.
BAD_TEXT = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def check_text(field: str, value: Any) -> None:
    """Refuse text that no export format can carry, anywhere in ``value`` (keys included).

    Walks mappings and lists; every string (and mapping key) must be free of :data:`BAD_TEXT`.

    Raises
    ------
    ConfigError
        Naming the field (``plan.uavs[0].flown_rectangle.rule``), the character's code point
        and what is allowed.
    """
    if isinstance(value, str):
        bad = BAD_TEXT.search(value)
        if bad is not None:
            kind = "a lone surrogate" if "\ud800" <= bad.group() <= "\udfff" else "a control"
            raise ConfigError(
                field,
                f"text with {kind} character U+{ord(bad.group()):04X} at {bad.start()}",
                "text without C0 control characters (tab, line feed and carriage return are "
                "allowed), U+FFFE, U+FFFF or lone surrogates",
            )
    elif isinstance(value, dict):
        for k, v in value.items():
            if isinstance(k, str):
                check_text(f"{field} key", k)
            check_text(f"{field}.{k}", v)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            check_text(f"{field}[{i}]", v)


def check_name(field: str, value: Any, most: int, *, empty: bool = False) -> str:
    """A name that every export can carry (an airfield's, a no-fly zone's): a string of at most
    ``most`` characters (at least one unless ``empty``) passing :func:`check_text`. The one
    rule for the scenario loader, ``scenario import`` and plan.json, so that a name accepted
    on the way in is never refused by an export.

    Raises
    ------
    ConfigError
        Naming ``field``, the value (shortened) and what is allowed.
    """
    lo = 0 if empty else 1
    if not isinstance(value, str) or not lo <= len(value) <= most:
        shown = value if not isinstance(value, str) or len(value) <= 80 else value[:77] + "..."
        got = shown if not isinstance(value, str) else f"{shown!r} ({len(value)} characters)"
        size = f"at most {most}" if empty else f"{lo}-{most}"
        raise ConfigError(field, got, f"a name of {size} characters")
    check_text(field, value)
    return value
