"""Parameter sets: the table (from the C++ core, the one source of truth),
defaults, and JSON / SSP (.ssv) files in the contract's format."""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from xml.sax.saxutils import quoteattr

from hdjoint import _core
from hdjoint.io.outputs import printable


class ParameterError(ValueError):
    """A parameter set that names an unknown parameter or a bad value."""


# Names a parameter file may still use from an earlier release, with the name
# that replaced them. They are refused (never silently ignored, never
# aliased): the error names each one and its replacement, so a file is
# migrated by renaming (docs/estimators.md, "Parameters").
RENAMED = {
    "jsf_Jl": "Jl",                      # the joint-state filter's copy of the joint's link inertia
    "jsf_Bl": "Bl",
    "jsf_mgl": "mgl",
    "jsf_motor_counts": "motor_counts",
    "jsf_link_counts": "link_counts",
}


# A key shaped like a parameter's name is named in a message; any other key, or a value that is no
# number, is described, never quoted: a parameter file may be a link to a file that is not one.
_NAME_SHAPED = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,39}\Z")


def _key(name) -> str:
    return f"'{name}'" if isinstance(name, str) and _NAME_SHAPED.match(name) else "(a key not shaped like a name)"


def _value(value) -> str:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return repr(value)
    return {str: "a string", bool: "true or false", list: "a list", dict: "an object", type(None): "null"}.get(
        type(value), "not a number")


@dataclass(frozen=True)
class ParameterInfo:
    name: str
    unit: str
    default: float
    min: float
    max: float
    scope: str  # "shared", "plant" or "estimator"
    description: str
    value_reference: int
    # The calibration prior (src/hdjoint/parameter_tolerance.def): NaN when never calibrated.
    tolerance_relative: float = math.nan
    tolerance_absolute: float = math.nan
    tolerance_source: str = ""

    def calibrated(self) -> bool:
        return not math.isnan(self.tolerance_relative)

    def tolerance(self, nominal: float, relative: float | None = None) -> float:
        """One standard deviation of the prior around `nominal`: max(relative*|nominal|, absolute)."""
        rel = self.tolerance_relative if relative is None else relative
        return max(rel * abs(nominal), self.tolerance_absolute)

    def in_estimator(self) -> bool:
        return self.scope in ("shared", "estimator")

    def in_plant(self) -> bool:
        return self.scope in ("shared", "plant")


@lru_cache(maxsize=1)
def table() -> dict[str, ParameterInfo]:
    """Every parameter by name, in the table's order."""
    return {row["name"]: ParameterInfo(**row) for row in _core.parameter_table()}


def unit_in_text(unit: str) -> str:
    """' N.m' to follow a value in a sentence; nothing for a ratio (unit "1")."""
    return "" if unit == "1" else f" {unit}"


def meaning(name: str) -> str:
    """A parameter's description cut to its first clause, to stand beside its symbol in a report
    (a clause that only points at an equation goes: "..., the nominal tau_fm of eq. (2)")."""
    first = re.split(r"; |: | \(|, eq\.", table()[name].description)[0]
    return re.sub(r",[^,]* eq\.$", "", first)


def values_in_text(values: dict[str, float], described: bool = False) -> str:
    """'omega_s = 20 rad/s, Kt_warmup_tc = 10 s': parameter values in a sentence
    (`described`: each after its meaning, 'Stribeck speed omega_s = 20 rad/s')."""
    return ", ".join(f"{meaning(n) + ' ' if described else ''}{n} = {v:.3g}{unit_in_text(table()[n].unit)}"
                     for n, v in values.items())


def encoder_step(counts: float) -> float:
    """One count of an encoder with `counts` per revolution, rad (0 counts: not quantised, 0 rad)."""
    return 2 * math.pi / counts if counts > 0 else 0.0


def defaults(scope: str = "all") -> dict[str, float]:
    """Default values for 'all', 'estimator' or 'plant'."""
    pick = {
        "all": lambda p: True,
        "estimator": ParameterInfo.in_estimator,
        "plant": ParameterInfo.in_plant,
    }[scope]
    return {name: info.default for name, info in table().items() if pick(info)}


@lru_cache(maxsize=1)
def _estimator_names() -> frozenset[str]:
    return frozenset(name for name, info in table().items() if info.in_estimator())


def for_estimator(params: dict[str, float]) -> dict[str, float]:
    """The subset of a parameter set the estimator takes (a KeyError names an unknown parameter)."""
    names = _estimator_names()
    out = {k: v for k, v in params.items() if k in names}
    if len(out) < len(params):
        info = table()
        for k in params:
            info[k]  # an unknown name raises, as it always did
    return out


def for_plant(params: dict[str, float]) -> dict[str, float]:
    """The subset of a parameter set the joint takes."""
    info = table()
    return {k: v for k, v in params.items() if info[k].in_plant()}


def check(params: dict, source: str = "parameter set") -> dict[str, float]:
    """Validate names, types and ranges; returns the set as floats."""
    info = table()
    if not isinstance(params, dict):
        raise ParameterError(f"{source}: expected a JSON object of name: value")
    renamed = [f"'{old}' is now '{RENAMED[old]}'" for old in params if old in RENAMED]
    if renamed:
        raise ParameterError(f"{source}: renamed parameter{'s' if len(renamed) > 1 else ''}: "
                             + "; ".join(renamed) + " (one joint, one parameter set: rename them; if the file sets "
                             "both names, keep the value that describes the joint)")
    checked = {}
    for name, value in params.items():
        if name not in info:
            raise ParameterError(f"{source}: unknown parameter {_key(name)}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{source}: parameter '{name}' must be a number, not {_value(value)}")
        try:
            value = float(value)
        except OverflowError:
            raise ParameterError(f"{source}: parameter '{name}' is too large a number") from None
        p = info[name]
        if not math.isfinite(value) or not p.min <= value <= p.max:
            raise ParameterError(
                f"{source}: parameter '{name}' = {value!r} is outside its valid range [{p.min}, {p.max}] {p.unit}")
        checked[name] = value
    problem = _core.check_parameters({**defaults(), **checked})  # rules across the table (encoder counts, delay)
    if problem is not None:
        raise ParameterError(f"{source}: {problem}")
    return checked


# The parameter file's key for the user's own calibration priors:
# {"Kt": 0.046, "tolerance": {"Kt": 0.1}} states Kt to +-10 % (relative).
TOLERANCE_KEY = "tolerance"


def _no_duplicates(pairs):
    seen = {}
    for key, value in pairs:
        if key in seen:
            raise ParameterError(f"{_key(key)} is given twice")
        seen[key] = value
    return seen


# The largest parameter file read, bytes: a parameter set with its statements is a few kilobytes.
MAX_FILE_BYTES = 1 << 20


def read_small_file(path, limit: int = MAX_FILE_BYTES) -> bytes | None:
    """PATH's bytes, or None when it holds more than LIMIT (only LIMIT + 1 are ever read: a
    device such as /dev/zero costs no memory). OSError when it cannot be read."""
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    return None if len(data) > limit else data


def _read_json(path) -> dict:
    shown = printable(path)
    try:
        data = read_small_file(path)
        if data is None:
            raise ParameterError(f"{shown}: larger than {MAX_FILE_BYTES // 1024} kB; a parameter file is a small "
                                 "JSON object of name: number (is this a parameter file?)")
        # utf-8-sig: a byte-order mark is tolerated, as in a recording.
        text = data.decode("utf-8-sig")
    except OSError as e:
        raise ParameterError(f"{shown}: cannot read the parameter file ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise ParameterError(f"{shown}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    path = shown
    try:
        data = json.loads(text, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as e:
        raise ParameterError(f"{path}: line {e.lineno}, column {e.colno}: not valid JSON ({e.msg})") from None
    except ParameterError as e:
        raise ParameterError(f"{path}: {e} (a parameter is set once)") from None
    except RecursionError:
        raise ParameterError(f"{path}: nested too deeply; a parameter file is one object of name: number") from None
    except ValueError as e:  # e.g. an integer of thousands of digits
        raise ParameterError(f"{path}: not a usable JSON number ({str(e).split(';')[0]})") from None
    if not isinstance(data, dict):
        raise ParameterError(f"{path}: expected a JSON object of name: value")
    return data


# A relative tolerance the diagnosis can use: from one part in a million to ten times the nominal value.
TOLERANCE_RANGE = (1e-6, 10.0)


def check_tolerances(overrides, source: str = "parameter set") -> dict[str, float]:
    """Validate the user's relative tolerances: known, calibrated parameters, finite and positive."""
    info = table()
    if not isinstance(overrides, dict):
        raise ParameterError(f"{source}: '{TOLERANCE_KEY}' must be an object of name: relative tolerance")
    checked = {}
    for name, value in overrides.items():
        if name not in info:
            raise ParameterError(f"{source}: '{TOLERANCE_KEY}' names an unknown parameter {_key(name)}")
        if not info[name].calibrated():
            raise ParameterError(f"{source}: '{TOLERANCE_KEY}' names '{name}', which the diagnosis never calibrates")
        lo, hi = TOLERANCE_RANGE
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:  # NaN fails too
            raise ParameterError(f"{source}: tolerance of '{name}' must be a positive number from {lo:g} to {hi:g} "
                                 f"(a fraction of the nominal value, 0.1 for +-10 %), not {_value(value)}")
        checked[name] = float(value)
    return checked


# What a parameter file may state about the joint's measurement, beside its
# parameters: {"accuracy": 2.0} asks the diagnosis for a model within 2 N.m
# RMS; {"sensor_noise": {"i_m": 0.004}} gives a datasheet's current noise
# (A RMS; "tau_sensor" in N.m RMS) in place of measuring it on the recording.
ACCURACY_KEY = "accuracy"
SENSOR_NOISE_KEY = "sensor_noise"
SENSOR_NOISE_UNITS = {"i_m": "A", "tau_sensor": "N.m"}


def _positive_number(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and 0.0 < value < math.inf


def check_accuracy(value, source: str = "parameter set") -> float | None:
    """The stated torque accuracy, N.m RMS (None when not stated)."""
    if value is None:
        return None
    if not _positive_number(value):
        raise ParameterError(f"{source}: '{ACCURACY_KEY}' must be a positive number of N.m (RMS), not {_value(value)}")
    return float(value)


def check_sensor_noise(stated, source: str = "parameter set") -> dict[str, float]:
    """The stated sensor noise, RMS per recording column ({} when not stated)."""
    if not isinstance(stated, dict):
        raise ParameterError(f"{source}: '{SENSOR_NOISE_KEY}' must be an object of column: RMS noise")
    for column, value in stated.items():
        if column not in SENSOR_NOISE_UNITS:
            raise ParameterError(f"{source}: '{SENSOR_NOISE_KEY}' names {_key(column)}; it states "
                                 f"{' and '.join(SENSOR_NOISE_UNITS)} (the encoders' noise is their counts)")
        if not _positive_number(value):
            raise ParameterError(f"{source}: noise of '{column}' must be a positive number of "
                                 f"{SENSOR_NOISE_UNITS[column]} (RMS), not {_value(value)}")
    return {column: float(value) for column, value in stated.items()}


# A documented parameter file (`hdjoint params --defaults`) also carries "about" (how to edit it, text) and
# "documentation" ({name: {"unit", "range", "description", "prior"}}): read back, the units are checked against
# the table and the rest is ignored.
ABOUT_KEY = "about"
DOCUMENTATION_KEY = "documentation"
NOT_PARAMETERS = (TOLERANCE_KEY, ACCURACY_KEY, SENSOR_NOISE_KEY, ABOUT_KEY, DOCUMENTATION_KEY)


def check_documentation(data: dict, source: str = "parameter set") -> None:
    """A documented file's "about" is text and its "documentation" names known parameters in their table units."""
    about = data.get(ABOUT_KEY, "")
    if not (isinstance(about, str) or isinstance(about, list) and all(isinstance(a, str) for a in about)):
        raise ParameterError(f"{source}: '{ABOUT_KEY}' must be text (or a list of lines)")
    documentation = data.get(DOCUMENTATION_KEY, {})
    if not isinstance(documentation, dict):
        raise ParameterError(f"{source}: '{DOCUMENTATION_KEY}' must be an object of name: {{unit, description, ...}}")
    info = table()
    for name, entry in documentation.items():
        if name not in info:
            raise ParameterError(f"{source}: '{DOCUMENTATION_KEY}' names an unknown parameter '{name}'")
        unit = entry.get("unit", info[name].unit) if isinstance(entry, dict) else info[name].unit
        if unit != info[name].unit:
            raise ParameterError(f"{source}: '{DOCUMENTATION_KEY}' gives '{name}' in {unit!r}; hdjoint takes it in "
                                 f"{info[name].unit!r} (convert the value, then the unit)")


# What `hdjoint estimate` takes from each recording unless a parameter file sets it: a documented file leaves
# them out (unless its source set them), so it serves recordings of any rate and jitter.
FROM_THE_RECORDING = {"Ts": "the recording's median step", "jsf_r_time": "measured on the recording"}


def documented(params: dict[str, float] | None = None, tolerance: dict[str, float] | None = None,
               keep: set[str] | frozenset[str] = frozenset()) -> dict:
    """PARAMS (None: the defaults) as a documented parameter file: every parameter's value (but
    FROM_THE_RECORDING's, unless named in KEEP), the relative tolerances (the table's priors, overridden by
    TOLERANCE), and each parameter's unit, range, description and prior; `load` reads it back as the same set."""
    info = table()
    values = {name: value for name, value in {**defaults(), **check(params or {})}.items()
              if name not in FROM_THE_RECORDING or name in keep}
    stated_tolerance = check_tolerances(tolerance or {})
    priors = {name: stated_tolerance.get(name, p.tolerance_relative) for name, p in info.items()
              if p.calibrated() and TOLERANCE_RANGE[0] <= stated_tolerance.get(name, p.tolerance_relative)
              <= TOLERANCE_RANGE[1]}

    def prior(name: str) -> str:
        p = info[name]
        if not p.calibrated():
            return "not calibrated by the diagnosis"
        source = f" ({p.tolerance_source})" if p.tolerance_source else ""
        if name not in priors:
            return f"{p.tolerance_absolute:g}{unit_in_text(p.unit)} (1 sigma, absolute){source}"
        absolute = f", at least {p.tolerance_absolute:g}{unit_in_text(p.unit)}" if p.tolerance_absolute > 0 else ""
        return f"{100 * priors[name]:g} % (1 sigma){absolute}{source}"

    return {ABOUT_KEY: ["An hdjoint parameter set (docs/estimators.md): name: value in SI units.",
                        "A file may set only some parameters; the rest take their defaults. Left out unless "
                        "set: " + ", ".join(f"{n} ({why})" for n, why in FROM_THE_RECORDING.items()) + ".",
                        f"'{TOLERANCE_KEY}': the diagnosis's priors, relative (0.1 = +-10 %, one standard "
                        "deviation); edit or delete them.",
                        f"Optional: '{ACCURACY_KEY}' (N.m RMS the verdict asks for), '{SENSOR_NOISE_KEY}' "
                        "({\"i_m\": A RMS, \"tau_sensor\": N.m RMS}).",
                        f"'{DOCUMENTATION_KEY}' is read only for its units, which must stay the table's."],
            **values,
            TOLERANCE_KEY: priors,
            DOCUMENTATION_KEY: {name: {"unit": p.unit, "range": [p.min, p.max], "default": p.default,
                                       "scope": p.scope, "description": p.description, "prior": prior(name),
                                       **({"left_out": f"{FROM_THE_RECORDING[name]} unless set here"}
                                          if name not in values else {})}
                                for name, p in info.items()}}


def save_documented(path: str | os.PathLike, params: dict[str, float] | None = None,
                    tolerance: dict[str, float] | None = None, keep: set[str] | frozenset[str] = frozenset()) -> None:
    """Write `documented(PARAMS, TOLERANCE, KEEP)` as JSON, atomically."""
    _atomic_write(path, json.dumps(documented(params, tolerance, keep), indent=2) + "\n")


def load(path: str | os.PathLike | None) -> dict[str, float]:
    """Defaults overridden by a JSON parameter file (None: defaults only).
    Its optional "tolerance", "accuracy" and "sensor_noise" entries are
    checked here and read by load_statements; "about" and "documentation"
    (a documented file's) are checked and otherwise ignored."""
    params = defaults()
    if path is None:
        return params
    data = _read_json(path)
    check_documentation(data, printable(path))
    data.pop(ABOUT_KEY, None)
    data.pop(DOCUMENTATION_KEY, None)
    check_tolerances(data.pop(TOLERANCE_KEY, {}), printable(path))
    check_accuracy(data.pop(ACCURACY_KEY, None), printable(path))
    check_sensor_noise(data.pop(SENSOR_NOISE_KEY, {}), printable(path))
    params.update(check(data, printable(path)))
    return params


def stated(path: str | os.PathLike | None) -> set[str]:
    """The parameters a file sets itself (the rest of a loaded set are defaults); none for None."""
    if path is None:
        return set()
    return set(_read_json(path)) - set(NOT_PARAMETERS)


def load_statements(path: str | os.PathLike | None) -> dict:
    """What a parameter file states beside its parameters, checked, as the
    diagnosis takes it: "tolerance" (relative, per parameter), "accuracy"
    (N.m, or None) and the sensors' "noise" ({} when none is stated)."""
    data = {} if path is None else _read_json(path)
    return {"tolerance": check_tolerances(data.get(TOLERANCE_KEY, {}), printable(path)),
            "accuracy": check_accuracy(data.get(ACCURACY_KEY), printable(path)),
            "noise": check_sensor_noise(data.get(SENSOR_NOISE_KEY, {}), printable(path))}


def load_tolerances(path: str | os.PathLike | None) -> dict[str, float]:
    """The user's relative tolerances from a parameter file ({} when it states none)."""
    return load_statements(path)["tolerance"]


def _atomic_write(path: str | os.PathLike, text: str) -> None:
    from hdjoint.io.outputs import write_whole
    write_whole(path, text)  # never over a link, a device node, a FIFO or a read-only file


def save(path: str | os.PathLike, params: dict[str, float], statements: dict | None = None) -> None:
    """Write a parameter set as JSON (contract format), atomically, with STATEMENTS ("tolerance", "accuracy",
    "sensor_noise", checked) after the values."""
    statements = dict(statements or {})
    check_tolerances(statements.get(TOLERANCE_KEY, {}))
    check_accuracy(statements.get(ACCURACY_KEY))
    check_sensor_noise(statements.get(SENSOR_NOISE_KEY, {}))
    _atomic_write(path, json.dumps({**check(params), **statements}, indent=2) + "\n")


def save_ssv(path: str | os.PathLike, params: dict[str, float], name: str = "hdjoint") -> None:
    """Write SSP 1.0 parameter values (.ssv) for the same set."""
    info = table()
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             (f'<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
             f' version="1.0" name={quoteattr(name)}>'),
             "  <ssv:Parameters>"]
    for key, value in check(params).items():
        unit = f" unit={quoteattr(info[key].unit)}" if info[key].unit != "1" else ""
        lines.append(f'    <ssv:Parameter name={quoteattr(key)}><ssv:Real value="{value!r}"{unit}/></ssv:Parameter>')
    lines += ["  </ssv:Parameters>", "</ssv:ParameterSet>", ""]
    _atomic_write(path, "\n".join(lines))
