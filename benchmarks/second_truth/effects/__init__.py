"""Planted missing physics, one effect per file, keyed by the contract's effect ID
(plus `kf_far_off`, a nominal parameter far from the truth)."""
from .backlash import Backlash
from .cogging import CoggingEffect
from .far_off import KfFarOff
from .gravity import Gravity
from .hysteresis import Hysteresis
from .kinematic_error import KinematicError
from .stribeck import Stribeck
from .time_delay import TimeDelay
from .viscous import Viscous
from .wave_generator import WaveGenerator

EFFECTS = {e.id: e for e in (Hysteresis, Backlash, CoggingEffect, KinematicError, Stribeck, Viscous,
                            TimeDelay, WaveGenerator, Gravity, KfFarOff)}
