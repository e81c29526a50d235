"""What every campaign target shares (:mod:`poc_env.agents.testing.campaign` and
:mod:`poc_env.agents.testing.campaign_files`): the silent-wrong-answer exception its checks
raise and the hostile scalar values its strategies draw."""

from __future__ import annotations

__all__ = ["SilentWrong", "check", "hostile_scalars"]


class SilentWrong(AssertionError):
    """A result that passed without an error but is wrong (a check failed)."""


def check(cond: bool, what: str) -> None:
    if not cond:
        raise SilentWrong(what)


def hostile_scalars():
    """Values that break naive parsers: every JSON/YAML scalar type and the float extremes."""
    from hypothesis import strategies as st

    return st.one_of(
        st.sampled_from(
            [
                None,
                True,
                False,
                "",
                "5",
                "1e3",
                "nan",
                "no",
                "abc",
                [],
                {},
                [1, 2],
                float("nan"),
                float("inf"),
                -float("inf"),
                1e308,
                -1e308,
                5e-324,
                0,
                0.0,
                -1,
                2**63,
                10**400,
                -(10**30),
                3.0,
                2.5,
            ]
        ),
        st.integers(min_value=-(10**6), max_value=10**6),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=8),
    )
