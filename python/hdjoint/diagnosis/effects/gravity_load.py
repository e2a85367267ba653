"""Gravity (or a payload) on the link."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw


class GravityLoad(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        pass  # the truth keeps its gravity; the nominal set has mgl = 0


EFFECT = GravityLoad(
    "gravity_load", "link", ("mgl",),
    "gravity (or payload) torque on the link", "mgl*sin(theta_l)", switched_by=("mgl",),
    starts=({"mgl": 1.0}, {"mgl": -1.0}), needs=("link_travel",),
    revealed_by="slow link motion over a wide angle", resizes=("mgl",), size=Size("mgl", source=TABLE_JOINT), rank=1)
