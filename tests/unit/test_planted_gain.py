"""What a planted effect would show (detection_limit.planted_gains): its gain
with what the residual already holds (an effect of the same sign hidden
there adds to it), and on its own. A residual that carries a large missed
structure of the effect's own shape lets a tiny planting gain through the
cross term alone; its own share tells that apart."""
import numpy as np

from hdjoint.diagnosis.verdict.detection_limit import planted_gains
from hdjoint.diagnosis.rules import MIN_GAIN

RNG = np.random.default_rng(5)
N = 20000
FOLD = np.repeat(np.arange(20), N // 20)
TEST = FOLD % 2 == 1
SHAPE = np.sign(np.sin(np.linspace(0.0, 60.0, N)))  # a loop's square wave


def _gains(base, left):
    return planted_gains(base[None, :], left[None, :], FOLD, TEST)


def test_a_tiny_planting_on_a_residual_already_of_its_shape_gains_only_through_the_cross_term():
    base = 0.3 * SHAPE + 0.05 * RNG.normal(size=N)  # a missed loop, 6 times the noise
    combined, alone = _gains(base, 0.002 * SHAPE)
    assert combined.gain > 0.01 and combined.z > 3.0   # over 1 % held out, on every fold
    assert 0.0 < alone.gain < MIN_GAIN / 50            # its own share: nothing


def test_on_a_residual_of_noise_both_agree_and_grow_with_the_planting():
    base = 0.05 * RNG.normal(size=N)
    small, large = _gains(base, 0.01 * SHAPE), _gains(base, 0.05 * SHAPE)
    for gain in small + large:
        assert gain.gain > MIN_GAIN and gain.z > 3.0
    assert abs(small[0].gain - small[1].gain) < 0.01 and max(g.gain for g in small) < min(g.gain for g in large)
    assert abs(large[1].gain - 0.5) < 0.03


class _StubPlanting:
    """A _Planting over a given residual: the effect's signature is `factor` times SHAPE, nothing calibrated away."""

    def __new__(cls, base):
        from types import SimpleNamespace
        from hdjoint.diagnosis.verdict.detection_limit import _Planting, reference_set
        from hdjoint.diagnosis.effects import EFFECTS
        from hdjoint.io.parameters import defaults
        planting = object.__new__(_Planting)
        effect = EFFECTS["stribeck_friction"]  # stationary: judged by the fold z against the null
        reference = reference_set(effect, defaults())
        planting.search = SimpleNamespace(objective=SimpleNamespace(fold=FOLD, test=TEST))
        planting.effect, planting.p, planting.at = effect, reference, None
        planting.reference, planting.anchor_jacobian = reference, None
        planting.base = base[None, :]
        planting.null = RNG.normal(size=48)  # fold z of noise: about N(0, 1)
        size = reference["Fs"]
        planting._residuals = lambda q: planting.base - (q["Fs"] / size) * SHAPE[None, :]
        return planting


def test_a_planting_shows_only_when_it_explains_enough_on_its_own():
    missed_loop = _StubPlanting(0.3 * SHAPE + 0.05 * RNG.normal(size=N))
    # 0.002: through the cross term alone over 1 % held out on every fold; on its own nothing.
    assert not missed_loop.shown(0.002)
    assert missed_loop.shown(0.05)  # its own share: about 2.5 %
    assert _StubPlanting(0.05 * RNG.normal(size=N)).shown(0.01)
