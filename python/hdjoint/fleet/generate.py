"""A simulated fleet with known drifts, for the proof and the docs: joints
of one robot recorded once a day on the paper experiment, each joint a few
percent off its nominal set (hdjoint.fmu.concealed_effects), and some joints with a
parameter growing linearly over the days."""
from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import date, timedelta
from pathlib import Path

from hdjoint.fmu import concealed_effects as cases, experiments
from hdjoint.io import parameters
from hdjoint.diagnosis import KINEMATIC_EQ7
from hdjoint.io.recording import write_recording
from hdjoint.io.outputs import write_whole


@dataclass(frozen=True)
class Drift:
    parameters: tuple[str, ...]  # scaled together
    per_day: float               # relative growth per day
    effect: str                  # the effect ID the fleet report should name


# 10 %/day: +50 % over the six days, beyond Fc's 30 % tolerance, which is
# what the diagnosis's priors and the fleet's relevance rule ask of a drift
# worth servicing (a drift within the tolerance the MAP fit may share with Stribeck).
FC_GROWTH = Drift(("Fc",), 0.10, "coulomb_friction")
KINEMATIC_GROWTH = Drift(KINEMATIC_EQ7, 0.15, "kinematic_error")
# Joint id -> its drift (None: none). Joints beyond these have none.
DEFAULT_DRIFTS = {"j2": FC_GROWTH, "j3": KINEMATIC_GROWTH}
FIRST_DAY = date(2026, 3, 2)
JOINT_PATTERN = r"logs/(?P<joint>robot\d+/j\d+)/(?P<date>\d{4}-\d{2}-\d{2})\.csv"


def joint_truth(drift: Drift | None, day: int) -> dict[str, float]:
    truth = cases.truth_for(cases.CASES[0])  # the control case: nominal errors only
    if drift:
        for name in drift.parameters:
            truth[name] *= 1.0 + drift.per_day * day
    return truth


def generate(out: str | Path, joints: int = 4, days: int = 6, duration: float = 20.0, robot: str = "robot1",
             drifts: dict[str, Drift] | None = None, progress=None) -> Path:
    """Write OUT/logs/<robot>/j<k>/<date>.csv, OUT/params/<robot>-j<k>.json, OUT/params-map.json and
    OUT/truth.json (which joints drift, in what); returns the params map's path."""
    out = Path(out)
    drifts = DEFAULT_DRIFTS if drifts is None else drifts
    nominal = cases.nominal_for(cases.CASES[0])
    pmap, truth_doc = {}, {}
    for k in range(1, joints + 1):
        joint = f"j{k}"
        drift = drifts.get(joint)
        params_file = out / "params" / f"{robot}-{joint}.json"
        params_file.parent.mkdir(parents=True, exist_ok=True)
        parameters.save(params_file, nominal)
        pmap[f"logs/{robot}/{joint}/*.csv"] = params_file.relative_to(out).as_posix()
        truth_doc[f"{robot}/{joint}"] = ({"parameters": list(drift.parameters), "per_day": drift.per_day,
                                          "effect": drift.effect} if drift else None)
        for day in range(days):
            path = out / "logs" / robot / joint / f"{FIRST_DAY + timedelta(days=day):%Y-%m-%d}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            rec = experiments.run("paper", joint=joint_truth(drift, day), nominal=nominal, duration=duration,
                                  sensors=experiments.Sensors(seed=1000 * k + day))
            write_recording(path, rec)
            if progress:
                progress(str(path))  # the path as written (OUT/logs/...), not relative to OUT
    write_whole(out / "truth.json", json.dumps({"drifts": truth_doc, "joint_pattern": JOINT_PATTERN}, indent=2))
    map_path = out / "params-map.json"
    write_whole(map_path, json.dumps(pmap, indent=2) + "\n")
    return map_path
