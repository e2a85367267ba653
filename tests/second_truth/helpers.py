"""Small builders shared by the second truth's tests."""
from __future__ import annotations

import numpy as np

from second_truth import nominal
from second_truth.forms.coulomb import Coulomb
from second_truth.forms.tan_law import TanLaw
from second_truth.joint import Ctx, Joint


def truth_params(**over) -> dict:
    truth, _ = nominal.draw(np.random.default_rng(7))
    truth.update(over)
    return truth


def joint(forms=None, **over) -> Joint:
    return Joint(truth_params(**over), forms if forms is not None else [TanLaw(), Coulomb(None, omega_c=0.3)])


def ctx(**kw) -> Ctx:
    c = Ctx()
    for k in Ctx.__slots__:
        setattr(c, k, 0.0)
    for k, v in kw.items():
        setattr(c, k, v)
    return c
