"""Error types of poc-env.

Every error raised for bad input names the field, the value and what is allowed, so that a
user can fix a YAML file or a call without reading a traceback from deep inside numpy.
"""

from __future__ import annotations

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


def require_extra(extra: str, what: str, *modules: str) -> None:
    """Raise :class:`MissingExtraError` unless every module in ``modules`` can be imported."""
    import importlib.util

    for m in modules:
        if importlib.util.find_spec(m) is None:
            raise MissingExtraError(extra, what)


class MapFileError(PocEnvError, ValueError):
    """A probability-map file is missing, unreadable or holds an invalid map."""


class GeometryError(PocEnvError, ValueError):
    """A polygon, circle or rectangle is degenerate, self-intersecting or out of range."""


def check_positive(field: str, value: Any, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a float if it is a finite number > 0 (>= 0 with ``allow_zero``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(field, value, "a number >= 0" if allow_zero else "a number > 0") from None
    if isinstance(value, bool) or not (x == x) or x in (float("inf"), float("-inf")):
        raise ConfigError(field, value, "a finite number")
    if x < 0 or (x == 0 and not allow_zero):
        raise ConfigError(field, value, "a number >= 0" if allow_zero else "a number > 0")
    return x


def check_range(field: str, value: Any, lo: float, hi: float) -> float:
    """Return ``value`` as a float if it is a finite number in ``[lo, hi]``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(field, value, f"a number in [{lo}, {hi}]") from None
    if isinstance(value, bool) or not (lo <= x <= hi):
        raise ConfigError(field, value, f"a number in [{lo}, {hi}]")
    return x
