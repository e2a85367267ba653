"""The calibration's deviation of the torque, propagated along its posterior's principal axes
(jobs/calibration_spread.py): for a torque linear in the parameters the axes' variances add up to
g' C g, C the covariance the intervals and correlations make; a parameter at its range's limit moves
no further."""
import numpy as np
import pytest
from scipy.stats import norm

from hdjoint.diagnosis.fit.priors import correlation
from hdjoint.diagnosis.rules import INTERVAL
from hdjoint.jobs.calibration_spread import PARAMETERS, _sets, principal_axes

Z = norm.ppf(0.5 + INTERVAL / 2.0)


def _entries(estimates: dict, sd: dict) -> dict:
    return {n: {"estimate": v, "lo": v - Z * sd[n], "hi": v + Z * sd[n]} for n, v in estimates.items()}


@pytest.mark.parametrize("r", [0.0, 0.5, -0.95])
def test_the_axes_carry_the_covariance_of_the_intervals_and_correlations(r):
    estimates, sd = {"Kf": 1.0e-4, "Fc": 0.05, "Jm": 3.0e-5}, {"Kf": 1.0e-5, "Fc": 0.01, "Jm": 2.0e-6}
    pairs = {("Kf", "Fc"): r, ("Kf", "Jm"): 0.3, ("Fc", "Jm"): -0.2}
    rho = {n: {} for n in estimates}
    for (a, b), value in pairs.items():
        rho[a][b] = rho[b][a] = value
    names, axes = principal_axes(_entries(estimates, sd), rho)
    s = np.array([sd[n] for n in names])
    full = np.array([[1.0 if a == b else rho[a][b] for b in names] for a in names]) * np.outer(s, s)
    g = np.array([2.0e4, -30.0, 1.0e5])  # a torque's sensitivity to each, N.m per unit
    assert np.sum((g @ axes) ** 2) == pytest.approx(g @ full @ g, rel=1e-9)


def test_parameters_that_trade_off_leave_little_of_the_torque():
    """Two estimates the recording knows only as a sum (r = -0.99): each interval is wide, the torque
    depending on their sum hardly moves, where independent intervals would add up."""
    estimates, sd = {"Kf": 1.0, "Fc": 1.0}, {"Kf": 0.1, "Fc": 0.1}
    rho = {"Kf": {"Fc": -0.99}, "Fc": {"Kf": -0.99}}
    _, axes = principal_axes(_entries(estimates, sd), rho)
    g = np.array([1.0, 1.0])
    assert np.sqrt(np.sum((g @ axes) ** 2)) < 0.15 * np.sqrt(2.0) * 0.1


def test_a_moved_parameter_stays_within_its_range():
    estimates = {"wg_load": 1.0, "Fc": 0.05}
    entries = _entries(estimates, {"wg_load": 0.01, "Fc": 0.01})
    sets = [ends for which, ends in _sets({"wg_load": 1.0, "Fc": 0.05}, entries, {}, estimates, 1.0, None)
            if which == PARAMETERS]
    assert sets and all(0.0 <= p["wg_load"] <= 1.0 for ends in sets for p in ends)
    assert any(p["wg_load"] < 1.0 for ends in sets for p in ends)


def test_a_correlation_matrix_is_read_off_a_covariance():
    cov = np.array([[4.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(correlation(cov), [[1.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1.0]])


def test_the_deviations_are_widened_in_place_and_every_other_cell_kept(tmp_path):
    from hdjoint.jobs.calibration_spread import CalibrationSpread, widen_deviations
    path = tmp_path / "est.csv"
    path.write_text("time,tau_hat,tau_hat_std,tau_smooth_std\n0.0,1.25,0.3,0.1\n0.001,1.5,0.4,0.2\n")
    spread = CalibrationSpread({"tau_hat_std": np.array([0.16, 0.09]), "tau_smooth_std": np.array([0.0, 0.0]),
                                "tau_ukf_std": np.array([1.0, 1.0])}, {})
    widen_deviations(str(path), spread)
    lines = path.read_text().splitlines()
    assert lines[0] == "time,tau_hat,tau_hat_std,tau_smooth_std"  # a deviation the file lacks is not added
    assert [line.split(",")[:2] for line in lines[1:]] == [["0.0", "1.25"], ["0.001", "1.5"]]
    np.testing.assert_allclose([float(line.split(",")[2]) for line in lines[1:]], [0.5, 0.5])  # 0.3^2 + 0.16, 0.4^2 + 0.09
    np.testing.assert_allclose([float(line.split(",")[3]) for line in lines[1:]], [0.1, 0.2])


def test_a_file_of_other_length_is_refused_and_left_as_it_was(tmp_path):
    from hdjoint.jobs.calibration_spread import CalibrationSpread, widen_deviations
    path = tmp_path / "est.csv"
    text = "time,tau_hat_std\n0.0,0.3\n0.001,0.4\n0.002,0.5\n"
    path.write_text(text)
    with pytest.raises(RuntimeError, match="est.csv: 3 rows for 2 samples"):
        widen_deviations(str(path), CalibrationSpread({"tau_hat_std": np.zeros(2)}, {}))
    assert path.read_text() == text and [p.name for p in tmp_path.iterdir()] == ["est.csv"]
