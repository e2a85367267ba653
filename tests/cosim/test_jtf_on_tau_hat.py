"""The torque loop closed on the joint-state filter's tau_hat
(JointTorqueFeedbackHat.ssp) runs in fmpy's SSP master, and the estimate it
feeds back follows the joint's torque through the load step."""
import numpy as np

from hdjoint import cosim


def test_jtf_on_tau_hat_runs_and_tracks_the_joint_torque():
    system = cosim.read_system(cosim.ssp_path("JointTorqueFeedbackHat"))
    assert ("estimator", "tau_hat", "controller", "tau_fb") in system.connections
    r = cosim.run_fmpy(cosim.ssp_path("JointTorqueFeedbackHat"), 4.0, 1e-3, {"controller.k_tau": 0.25})
    after = r.time > 1.0
    error = (r["estimator.tau_hat"] - r["joint.tau_joint"])[after]
    assert np.sqrt(np.mean(error ** 2)) < 0.2
    # Under the 2 N.m load (stepped in at 2 s) as well: the loop stays stable and the estimate follows.
    loaded = (r.time > 2.5) & (r.time < 4.0)  # the step ramps in over its first 0.1 s
    assert np.ptp(r["controller.tau_ext"][loaded]) == 0.0 and abs(r["controller.tau_ext"][loaded][0]) > 1.0
    assert np.sqrt(np.mean((r["estimator.tau_hat"] - r["joint.tau_joint"])[loaded] ** 2)) < 0.2
