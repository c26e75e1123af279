"""The hypothesis sets of an object, cached per process: the benchmark's (METHOD §3a) and
the brute-force ones (§3b).
"""

from __future__ import annotations

from functools import lru_cache

from app.model.objects import load_object
from app.sim.bruteforce import BF_SETS
from app.sim.bruteforce import brute_force_hypotheses as _bf_hypotheses
from app.sim.hypotheses import Hypotheses, hypotheses_for


@lru_cache(maxsize=32)
def cached_hypotheses(key: str) -> Hypotheses:
    """The anthropomorphic hypotheses of an object (per process)."""
    return hypotheses_for(load_object(key))


#: Hypothesis sets: the benchmark's (METHOD §3a) and the brute-force ones (§3b).
HYPOTHESIS_SETS: tuple[str, ...] = ("anthropomorphic", *BF_SETS)


def check_set(hypothesis_set: str) -> None:
    if hypothesis_set not in HYPOTHESIS_SETS:
        from app.errors import SettingsError

        raise SettingsError(
            f"unknown hypothesis set {hypothesis_set!r}; choose one of {HYPOTHESIS_SETS}"
        )


@lru_cache(maxsize=32)
def hypotheses_of(key: str, hypothesis_set: str = "anthropomorphic") -> Hypotheses:
    """The hypotheses of an object in a set of ``HYPOTHESIS_SETS`` (per process)."""
    check_set(hypothesis_set)
    if hypothesis_set == "anthropomorphic":
        return cached_hypotheses(key)
    return _bf_hypotheses(load_object(key), BF_SETS[hypothesis_set])
