"""What the calibration makes of the independent truth's sweep controls
(motor_rest.py says why the motor at rest matters): each seed's drawn truth,
and the same truth changed in one thing (its friction law made tanh with the
same Fc and omega_fc; its structural damping Df set to 0), calibrated as
the diagnosis does. Prints Jm and Kt as multiples of their nominal values,
their distance from the truth in tolerances, and every other calibrated
parameter beyond 3 tolerances.

  python benchmarks/sweep_calibration.py [--seeds 4]

writes docs/results/sweep_calibration.md."""
from __future__ import annotations

import argparse
import time

from threadpoolctl import threadpool_limits

from hdjoint.diagnosis.fit.nominal_calibration import calibrate, calibration_table
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint_truth import cases as tc
from hdjoint_truth.simulate import simulate
from results import ResultsPage

VARIANTS = {
    "as drawn": lambda joint: None,
    "tanh friction": lambda joint: setattr(joint.form, "friction", "tanh"),
    "Df = 0": lambda joint: joint.truth.update(Df=0.0),
}


def calibrated(joint) -> tuple[dict, Objective, object]:
    with threadpool_limits(limits=1, user_api="blas"):
        result = calibrate(prepare(simulate(joint.truth, joint.form, joint.setups[0], joint.nominal), joint.nominal,
                                   workers=1))
    return result.params, result.objective, result.fit


def row(seed: int, variant: str, joint, p: dict, diag: Objective, fit, seconds: float) -> str:
    def cell(name):
        off = (p[name] - joint.truth[name]) / diag.priors[name].std
        return f"{p[name] / joint.nominal[name]:.2f}x (truth {joint.truth[name] / joint.nominal[name]:.2f}x, {off:+.1f})"
    others = [f"{n} {c.z:+.1f}" for n, c in calibration_table(diag, fit, p).items()
              if n not in ("Jm", "Kt") and c.beyond_tolerance]
    return (f"| {seed} | {variant} | {joint.form.friction} | {cell('Jm')} | {cell('Kt')} | "
            f"{', '.join(others) or '-'} | {seconds:.0f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    args = ap.parse_args()
    page = ResultsPage("sweep_calibration", "Calibration on the independent truth's sweep controls",
                       f"python benchmarks/sweep_calibration.py --seeds {args.seeds}")
    page.say("Jm, Kt: calibrated / nominal (the truth's / nominal; calibrated - truth in tolerances). "
             "Others: calibrated parameters beyond 3 tolerances of their nominal value (z).")
    page.say("| seed | truth | friction | Jm | Kt | others beyond tolerance | s |")
    page.say("|---|---|---|---|---|---|---|")
    case = next(c for c in tc.CONTROL_CASES if c.excitation == "sweep")
    for seed in range(args.seeds):
        for variant, change in VARIANTS.items():
            joint = tc.draw(case, seed)
            if variant == "tanh friction" and joint.form.friction == "tanh":
                continue  # already the drawn truth
            change(joint)
            start = time.perf_counter()
            p, diag, fit = calibrated(joint)
            page.say(row(seed, variant, joint, p, diag, fit, time.perf_counter() - start))
    page.write()


if __name__ == "__main__":
    main()
