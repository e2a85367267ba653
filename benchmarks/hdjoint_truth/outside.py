"""Physics a real harmonic drive can have that the diagnosis's effect library
does not name (its open-library fallback must say something of it), and a
friction law of another form than the library's (a control: nothing is
missing). Each plants itself into a drawn truth; sizes are drawn per seed
with the reason for their scale beside them.

  friction_ripple   motor friction varying with the motor angle: the wave
                    generator's elliptic bearing carries the flexspline's
                    two lobes round twice per motor revolution, so its
                    rolling friction has order 2 in theta_m (Tuttle &
                    Seering 1996, IEEE Trans. Robot. Autom. 12(3), measured
                    friction ripple at the wave generator's frequency)
  kinematic_torque  a kinematic error whose wave-generator-order amplitude
                    grows with the transmitted torque: the teeth mesh
                    deeper as the flexspline twists (Ghorbel, Gandhi &
                    Alpeter 1998, J. Mech. Des. 120: the transmission error
                    changes with load)
  friction_load     Coulomb friction rising with the transmitted torque: the
                    teeth's and the bearing's normal forces grow with it
                    (Hamon, Gautier & Garrec 2010, IROS, load-dependent dry
                    friction; a harmonic drive loses 10-25 % of its power at
                    rated load)
  lugre             the LuGre bristle law in place of the tanh law (a form,
                    not an effect: the control)
"""
from __future__ import annotations

from hdjoint_truth.physics import Form

RIPPLE_ORDER = 2.0  # per motor revolution: the wave generator's two lobes


def friction_ripple(truth: dict, form: Form, sensor, rng) -> None:
    """Coulomb level times 1 + r*cos(2*theta_m), its amplitude Fc*r about 7
    (5-9) times the current sensor's white noise in motor torque (Kt*noise):
    what a recording shows plainly, well beyond noise, and 10-40 % of a
    Coulomb level, as a bearing's load ripple."""
    r = float(rng.uniform(5.0, 9.0)) * truth["Kt"] * sensor.white / truth["Fc"]
    form.friction_ripple = (RIPPLE_ORDER, min(r, 0.5))


def kinematic_torque(truth: dict, form: Form, sensor, rng) -> None:
    """theta_err += c*tau_f*cos(2*theta_m), c 3-5e-6 rad per N.m: at the
    paper's 5 N.m test torque 1.5-2.5e-5 rad, the size of eq. (7)'s own
    second wave-generator harmonic (aw2 = 2e-5 rad), a few link encoder counts."""
    form.kinematic_torque = (RIPPLE_ORDER, float(rng.uniform(3e-6, 5e-6)))


def friction_load(truth: dict, form: Form, sensor, rng) -> None:
    """Coulomb level + mu*|tau_f|/N, mu 0.05-0.08: 5-8 % of the transmitted
    torque lost to load-dependent dry friction, within a harmonic drive's
    efficiency loss at rated load."""
    form.friction_load = float(rng.uniform(0.05, 0.08))


def lugre(truth: dict, form: Form, sensor, rng) -> None:
    """The drawn joint's friction as LuGre's bristles (their stiffness and
    damping as drawn for every truth), integrated as LuGre always is here."""
    form.friction, form.integrator, form.substeps = "lugre", "semi_implicit", 10


LAWS = {"friction_ripple": friction_ripple, "kinematic_torque": kinematic_torque, "friction_load": friction_load,
        "lugre": lugre}
