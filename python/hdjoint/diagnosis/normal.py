"""The standard normal distribution's cdf, sf, ppf and isf: the special
functions scipy.stats.norm evaluates (ndtr, ndtri), the same numbers,
without importing scipy.stats, whose distributions' docstrings take a
third of a second to build when `hdjoint diagnose` starts."""
from __future__ import annotations

from scipy.special import ndtr, ndtri


def cdf(x):
    return ndtr(x)


def sf(x):
    return ndtr(-x)


def ppf(q):
    return ndtri(q)


def isf(q):
    return -ndtri(q)
