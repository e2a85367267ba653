"""The calibration's priors (parameter_tolerance.def through the table, the
parameter file's "tolerance" key) and the significance machinery's pieces."""
import json

import numpy as np
import pytest

from hdjoint.io import parameters
from hdjoint.diagnosis.fit.priors import Calibrated, Prior, priors
from hdjoint.diagnosis.effects import calibrated_parameters
from hdjoint.diagnosis.search.significance import NullNoise, benjamini_hochberg, null_z
from hdjoint.diagnosis.model.kinematics import folds


def test_the_table_carries_cited_tolerances():
    table = parameters.table()
    assert table["Kt"].tolerance(0.045) == pytest.approx(0.05 * 0.045)
    assert table["Kf"].tolerance(1e4) == pytest.approx(2e3)
    assert table["aw1"].tolerance(6e-5) == pytest.approx(6e-5)  # kinematic error: +-100 %
    assert table["aw1"].tolerance(0.0) > 0  # an absolute floor where the nominal value is zero
    assert "catalogue" in table["Kt"].tolerance_source
    assert not table["N"].calibrated()


def test_everything_the_diagnosis_calibrates_has_a_prior():
    nominal = dict(parameters.defaults(), wg_load=1.0, Fs=0.01, hys_H=0.2, backlash=1e-5, cog_a=1e-3, Fl=0.1,
                   i_delay=1e-3, Fc_drift=1e-4, ke_m1_a=1e-6, ke_l1_b=1e-6)
    for part in ("transmission", "motor", "link"):
        names = calibrated_parameters(part, nominal, True)
        assert set(names) == set(priors(names, nominal, {}))
    assert "omega_fc" in calibrated_parameters("motor", nominal, True)  # a shape parameter is calibrated too
    # An effect switched off is not calibrated through its shape (hys_sigma means nothing while hys_H = 0).
    assert "hys_sigma" not in calibrated_parameters("transmission", parameters.defaults(), True)


def test_a_parameter_file_states_tolerances(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"Kt": 0.05, "tolerance": {"Kt": 0.1, "Kf": 0.5}}))
    assert parameters.load(path)["Kt"] == 0.05
    tolerance = parameters.load_tolerances(path)
    assert tolerance == {"Kt": 0.1, "Kf": 0.5}
    assert priors(["Kt"], {"Kt": 0.05}, tolerance)["Kt"] == Prior(0.05, pytest.approx(0.005))


@pytest.mark.parametrize("tolerance,message", [({"Kx": 0.1}, "unknown parameter 'Kx'"),
                                               ({"N": 0.1}, "never calibrates"),
                                               ({"Kt": -1}, "positive number"),
                                               ([0.1], "must be an object")])
def test_a_bad_tolerance_is_refused_by_name(tmp_path, tolerance, message):
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"tolerance": tolerance}))
    with pytest.raises(parameters.ParameterError, match=message):
        parameters.load(path)


def test_a_resized_parameter_is_judged_against_its_tolerance():
    c = Calibrated("aw1", 6e-6, 6e-5, 1e-6, Prior(6e-6, 1e-5))
    assert c.z == pytest.approx(5.4) and c.beyond_tolerance and c.identified
    lo, hi = c.interval
    assert lo < 6e-5 < hi and hi - lo == pytest.approx(2 * 1.96e-6, rel=1e-3)
    assert not Calibrated("aw1", 6e-6, 2e-5, 1e-5, Prior(6e-6, 1e-5)).beyond_tolerance


def test_benjamini_hochberg_matches_the_step_up_rule():
    # R's p.adjust(c(0.01, 0.04, 0.03, 0.2), "BH") = 0.04, 0.0533, 0.0533, 0.2
    assert benjamini_hochberg([0.01, 0.04, 0.03, 0.2]) == pytest.approx([0.04, 0.16 / 3, 0.16 / 3, 0.2])


def test_null_noise_keeps_the_residuals_colour_and_loses_their_structure():
    rng = np.random.default_rng(3)
    n = 4096
    t = np.arange(n)
    coloured = np.convolve(rng.normal(size=n), np.ones(20) / 20, mode="same") + 0.5 * np.sin(2 * np.pi * t / 512)
    replicates = NullNoise(coloured[None, :]).replicates([0])
    assert replicates.shape[1:] == (1, n)
    power = np.abs(np.fft.rfft(coloured)) ** 2
    assert np.allclose(np.abs(np.fft.rfft(replicates[0, 0])) ** 2, power, rtol=1e-6, atol=1e-9)
    # The sine's phase is gone: each replicate projects on it differently.
    projections = replicates[:, 0, :] @ np.sin(2 * np.pi * t / 512)
    assert np.std(projections) > 0.1 * abs(coloured @ np.sin(2 * np.pi * t / 512))


def test_the_simulated_null_of_a_structureless_regressor_is_centred_below_significance():
    rng = np.random.default_rng(5)
    n = 8000
    fold = folds(n, 40)
    train, test = fold % 2 == 0, fold % 2 == 1
    noise = NullNoise(np.convolve(rng.normal(size=n), np.ones(15) / 15, mode="same")[None, :]).replicates([0])
    jac = rng.normal(size=(1, n, 2))
    z = null_z(noise, jac, np.flatnonzero(train), fold, test)
    assert abs(np.mean(z)) < 1.5 and np.mean(z > 3.0) < 0.1


def test_a_binned_structure_is_significant_against_the_simulated_null_and_noise_is_not():
    """The unexplained-structure scans' test (findings.remaining_structure): bins as regressors."""
    from hdjoint.diagnosis.search.significance import p_value
    from hdjoint.diagnosis.model.structure import bins_of, held_out_gain
    rng = np.random.default_rng(8)
    n = 8000
    fold = folds(n, 40)
    train, test = fold % 2 == 0, fold % 2 == 1
    speed = np.sin(np.arange(n) / 300.0)
    noise = np.convolve(rng.normal(size=n), np.ones(10) / 10, mode="same")
    for structure, significant in ((1.0 * np.sign(speed) * noise.std(), True), (0.0, False)):
        r = noise + structure
        index, _, _ = bins_of(speed, r)
        bins = np.zeros((1, n, index.max() + 2))
        bins[0, np.arange(n), index] = 1.0
        bins[0, :, -1] = 1.0
        coef = np.linalg.lstsq(bins[0][train], r[train], rcond=None)[0]
        z = held_out_gain(r, bins[0] @ coef, fold, test).z
        p = p_value(z, null_z(NullNoise(r[None, :]).replicates([0]), bins, np.flatnonzero(train), fold, test))
        assert (p < 0.01) == significant, (z, p)


def test_the_vectorised_null_statistic_is_the_held_out_gain_z_of_each_replicate():
    from hdjoint.diagnosis.model.structure import held_out_gain_sq
    rng = np.random.default_rng(1)
    n = 6000
    fold = folds(n, 40)
    train, test = fold % 2 == 0, fold % 2 == 1
    noise = NullNoise(rng.normal(size=(2, n))).replicates([0, 1])
    jac = rng.normal(size=(2, n, 3))
    fit_rows = np.flatnonzero(train)[::2]
    reference = []
    for b in range(len(noise)):
        delta = np.linalg.lstsq(jac[:, fit_rows, :].reshape(-1, 3), noise[b][:, fit_rows].reshape(-1), rcond=None)[0]
        change = np.einsum("csk,k->cs", jac, delta)
        reference.append(held_out_gain_sq((noise[b] ** 2).sum(0), ((noise[b] - change) ** 2).sum(0), fold, test).z)
    np.testing.assert_allclose(null_z(noise, jac, fit_rows, fold, test), reference, rtol=1e-9, atol=1e-9)
