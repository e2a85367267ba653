"""Friction on the link side (output bearing, seals). Its smoothing omega_fl
is fitted with it: a link friction that switches at the wrong speed leaves
structure at low link speed on the next recording."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, Size, TruthDraw


class LinkFriction(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth["Fl"] = 0.25 * draw.scaled()


EFFECT = LinkFriction(
    "link_friction", "link", ("Fl", "omega_fl"),
    "friction on the link side (output bearing, seals)", "Fl*tanh(omega_l/omega_fl)", switched_by=("Fl",),
    starts=({"Fl": 0.05, "omega_fl": 0.01}, {"Fl": 0.3, "omega_fl": 0.01}, {"Fl": 0.3, "omega_fl": 0.003}),
    needs=("link_reversals",), revealed_by="link reversals at low motor current", resizes=("Fl", "omega_fl"),
    size=Size("Fl", reference=(("Fl", 0.05),)), rank=2)
