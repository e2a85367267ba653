"""Model forms and sensor nuisances, one plug-in per file (see base.py).

FAMILIES lists, per family, the forms a case may draw (None: the family's
effect absent), its baseline (what a case without variation uses) and whether
the family is held out: tuning seeds only ever get a held-out family's
baseline, so its other forms stay unseen until the sealed seeds.
"""
from __future__ import annotations

from .catalogue_stiffness import CatalogueStiffness
from .cogging import Cogging
from .coulomb import Coulomb
from .current_sensor import CurrentSensor
from .dahl import Dahl
from .dropped_samples import DroppedSamples
from .encoder import EncoderFloor, EncoderRound
from .gms import GMS
from .load_friction import LoadFriction
from .loss_factor import LossFactor
from .lugre import LuGre
from .reading_jitter import ReadingJitter
from .stamp_jitter import StampJitter
from .structural_damping import StructuralDamping
from .tan_law import TanLaw
from .thermal_friction import ThermalFriction
from .torque_sensor import TorqueSensor

FAMILIES = {
    "motor_friction": {"forms": (Coulomb, LuGre, GMS, ThermalFriction, LoadFriction), "baseline": Coulomb, "held_out": False},
    "stiffness_law": {"forms": (TanLaw, CatalogueStiffness), "baseline": TanLaw, "held_out": True},
    "transmission_loss": {"forms": (None, StructuralDamping, LossFactor), "baseline": None, "held_out": False},
    "current_sensor": {"forms": (CurrentSensor,), "baseline": CurrentSensor, "held_out": False},
    "encoder": {"forms": (EncoderFloor, EncoderRound), "baseline": EncoderFloor, "held_out": False},
    "timing": {"forms": (None, ReadingJitter, StampJitter), "baseline": None, "held_out": False},
    "dropouts": {"forms": (None, DroppedSamples), "baseline": None, "held_out": False},
    "torque_sensor": {"forms": (TorqueSensor,), "baseline": TorqueSensor, "held_out": False},
}
HELD_OUT = tuple(k for k, v in FAMILIES.items() if v["held_out"])
BY_NAME = {cls.name: cls for fam in FAMILIES.values() for cls in fam["forms"] if cls is not None}
BY_NAME.update({Dahl.name: Dahl, Cogging.name: Cogging})
