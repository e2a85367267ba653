"""The shipped FMUs are valid FMI 2.0 Co-Simulation FMUs and expose exactly the
contract's interface (CONTRACT.md) and the parameter table."""
from __future__ import annotations

import re
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import fmpy
import pytest
from fmpy.validation import validate_fmu

from hdjoint.io import parameters
from hdjoint.fmu.shipped import fmu_path

from hdjoint import _core
from conftest import ESTIMATOR, FMU_NAMES, JOINT

REPO = Path(__file__).resolve().parents[2]

# name: (causality, unit) -- CONTRACT.md, "Two FMUs".
CONTRACT = {
    ESTIMATOR: {
        "i_m": ("input", "A"),
        "theta_m": ("input", "rad"),
        "theta_l": ("input", "rad"),
        "tau_ukf": ("output", "N.m"),
        "tau_compliance": ("output", "N.m"),
        "omega_m": ("output", "rad/s"),
        "dtheta_f": ("output", "rad"),
        "tau_ukf_std": ("output", "N.m"),
    },
    JOINT: {
        "i_m": ("input", "A"),
        "tau_ext": ("input", "N.m"),
        "theta_m": ("output", "rad"),
        "theta_l": ("output", "rad"),
        "tau_joint": ("output", "N.m"),
        "omega_m": ("output", "rad/s"),
        # CONTRACT.md's omega_l output, renamed because the eq. (7) parameter is omega_l.
        "omega_link": ("output", "rad/s"),
    },
}


def declared_outputs(name: str) -> dict[str, tuple[str, str]]:
    """The FMU's outputs as its signal table (src/hdjoint/*_signals.def) declares them: an output beyond
    the contract's is an addition, documented by its row (unit and description) on the FMU's own page."""
    rows = _core.fmu_signals()[name]
    for row in rows:
        assert row["kind"] != "output" or row["description"].strip(), f"{name}.{row['name']}: no description"
    return {row["name"]: ("output", row["unit"]) for row in rows if row["kind"] == "output"}

# "One joint, one parameter set": the link and encoders are shared too.
CONTRACT_SHARED = ["N", "Kt", "Jm", "Bm", "Fc", "Kf", "Cf", "Kw", "Cw", "a0", "al1", "bl1", "omega_l",
                   "aw1", "bw1", "aw2", "bw2", "omega_w", "Jl", "Bl", "mgl", "motor_counts", "link_counts"]
CONTRACT_PLANT_ONLY = []
CONTRACT_ESTIMATOR_ONLY = ["ukf_alpha", "ukf_beta", "ukf_kappa"]

# HarmonicDriveJoint's Model Exchange variables (plant_signals.def: HDJ_PLANT_STATES, HDJ_PLANT_EVENT_INDICATORS).
ME_STATES = ("motor_angle", "motor_speed", "link_angle", "link_speed", "z_dahl", "z_bouc_wen", "z_lugre")
ME_LOCALS = (*ME_STATES, *(f"der({s})" for s in ME_STATES), "backlash_upper", "backlash_lower")

# SI base-unit exponents (kg, m, s, A, rad) of the units the contract uses.
BASE_UNITS = {
    "A": dict(A=1), "rad": dict(rad=1), "rad/s": dict(rad=1, s=-1), "N.m": dict(kg=1, m=2, s=-2),
    "s": dict(s=1), "N.m/A": dict(kg=1, m=2, s=-2, A=-1), "N.m/rad": dict(kg=1, m=2, s=-2, rad=-1),
    "kg.m2": dict(kg=1, m=2), "N.m.s/rad": dict(kg=1, m=2, s=-1, rad=-1), "1/(N.m)": dict(kg=-1, m=-2, s=2),
    "1/rad": dict(rad=-1), "1": {}, "1/s": dict(s=-1),
    "N.m/s": dict(kg=1, m=2, s=-3), "rad/s2": dict(rad=1, s=-2),
}


def in_scope(name: str, info: parameters.ParameterInfo) -> bool:
    return info.in_estimator() if name == ESTIMATOR else info.in_plant()


@pytest.fixture(scope="module", params=FMU_NAMES)
def fmu(request):
    path = fmu_path(request.param)
    return request.param, path, fmpy.read_model_description(str(path))


def variables(md):
    return {v.name: v for v in md.modelVariables}


def test_validate_fmu_reports_no_problems(fmu):
    name, path, _ = fmu
    assert validate_fmu(str(path)) == []


def test_model_identifier_and_fmi_version(fmu):
    name, path, md = fmu
    assert md.fmiVersion == "2.0"
    assert md.coSimulation is not None
    # Model Exchange: the joint only (its continuous states; tests/fmu/test_model_exchange.py).
    assert (md.modelExchange is not None) == (name == JOINT)
    assert md.coSimulation.modelIdentifier == name
    assert md.modelName == name
    assert path.name == f"{name}.fmu"


def test_inputs_and_outputs_match_contract(fmu):
    name, _, md = fmu
    v = variables(md)
    required, later = CONTRACT[name], declared_outputs(name)
    for var, (causality, unit) in required.items():
        assert var in v, f"{name}: contract variable {var} missing"
        assert v[var].causality == causality, f"{name}.{var}: causality {v[var].causality}, contract {causality}"
        assert v[var].unit == unit, f"{name}.{var}: unit {v[var].unit!r}, contract {unit!r}"
        assert v[var].type == "Real"
    # Inputs exactly the contract's; outputs the contract's and the declared additions.
    inputs = {n for n, x in v.items() if x.causality == "input"}
    outputs = {n for n, x in v.items() if x.causality == "output"}
    assert inputs == {n for n, (c, _) in required.items() if c == "input"}
    allowed = {**required, **later}
    assert outputs <= {n for n, (c, _) in allowed.items() if c == "output"}, outputs
    for var in outputs:
        assert v[var].unit == allowed[var][1]
    # Beyond those, only the joint's Model Exchange states, derivatives and event indicators, as locals.
    me = set(ME_LOCALS) if name == JOINT else set()
    assert {n for n, x in v.items() if x.causality not in ("input", "output", "parameter")} == me
    assert all(v[n].causality == "local" for n in me)


def test_outputs_are_calculated_and_continuous(fmu):
    _, _, md = fmu
    for var in md.modelVariables:
        if var.causality == "output":
            assert var.variability == "continuous" and var.initial == "calculated", var.name
        if var.causality == "input":
            assert var.variability == "continuous" and var.start is not None, var.name


def test_parameters_match_table(fmu):
    name, _, md = fmu
    v = variables(md)
    table = parameters.table()
    expected = {n for n, info in table.items() if in_scope(name, info)}
    present = {n for n, x in v.items() if x.causality == "parameter"}
    assert present == expected, (f"{name}: parameters missing {sorted(expected - present)}, "
                                 f"not in the table/scope {sorted(present - expected)}")
    for pname in sorted(expected):
        info, var = table[pname], v[pname]
        assert var.type == "Real"
        assert var.variability in ("fixed", "tunable"), pname
        assert var.unit == info.unit, f"{pname}: unit {var.unit!r} vs table {info.unit!r}"
        assert float(var.start) == info.default, f"{pname}: start {var.start} vs default {info.default!r}"
        assert float(var.min) == info.min, f"{pname}: min {var.min} vs {info.min!r}"
        assert float(var.max) == info.max, f"{pname}: max {var.max} vs {info.max!r}"
        assert var.valueReference == info.value_reference, pname
        assert var.description, f"{pname} has no description"
        assert info.min <= info.default <= info.max, pname


def test_contract_parameter_names_and_scopes(fmu):
    name, _, md = fmu
    v = variables(md)
    wanted = CONTRACT_SHARED + (CONTRACT_ESTIMATOR_ONLY if name == ESTIMATOR else CONTRACT_PLANT_ONLY)
    unwanted = CONTRACT_PLANT_ONLY if name == ESTIMATOR else CONTRACT_ESTIMATOR_ONLY
    for p in wanted:
        assert p in v and v[p].causality == "parameter", f"{name}: contract parameter {p} missing"
    for p in unwanted:
        assert p not in v, f"{name}: {p} belongs to the other FMU"
    # The joint-state filter's former copies of the joint's parameters are gone.
    assert not [p for p in v if p in parameters.RENAMED], f"{name}: carries a removed jsf_* copy"


def test_value_references_unique_per_causality(fmu):
    _, _, md = fmu
    refs = [v.valueReference for v in md.modelVariables]
    assert len(refs) == len(set(refs))


def test_units_are_defined_with_correct_base_units(fmu):
    _, _, md = fmu
    defined = {u.name: u for u in md.unitDefinitions}
    for var in md.modelVariables:
        assert var.unit in defined, f"{var.name}: unit {var.unit!r} not in UnitDefinitions"
    for uname, unit in defined.items():
        assert uname in BASE_UNITS, f"unexpected unit {uname!r}"
        b = unit.baseUnit
        got = {k: getattr(b, k) for k in ("kg", "m", "s", "A", "rad") if getattr(b, k)}
        assert got == BASE_UNITS[uname], f"{uname}: base units {got}"
        assert b.factor == 1.0 and b.offset == 0.0


def test_capability_flags(fmu):
    _, _, md = fmu
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize is True
    assert cs.canGetAndSetFMUstate is True
    assert cs.canSerializeFMUstate is True
    assert cs.canBeInstantiatedOnlyOncePerProcess is False


def test_model_structure_lists_every_output(fmu):
    _, _, md = fmu
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert [u.variable.name for u in md.outputs] == outputs
    # FMI 2.0: outputs with initial="calculated" must appear in InitialUnknowns, and
    # in Model Exchange the states and their derivatives too.
    me = [v.name for v in md.modelVariables if v.name in ME_STATES or v.name.startswith("der(")]
    assert [u.variable.name for u in md.initialUnknowns] == outputs + me
    # Outputs change only in doStep: no direct feedthrough from an input.
    for u in md.outputs:
        assert all(d.causality != "input" for d in (u.dependencies or [])), u.variable.name


def test_default_experiment_is_sane(fmu):
    _, _, md = fmu
    de = md.defaultExperiment
    assert de is not None and float(de.stepSize) == 1e-3 and float(de.stopTime) > float(de.startTime)


def test_zip_holds_documentation_sources_and_binary(fmu):
    name, path, md = fmu
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        assert "modelDescription.xml" in names
        assert f"binaries/linux64/{name}.so" in names
        assert "documentation/index.html" in names
        html = z.read("documentation/index.html").decode("utf-8")
        for var in md.modelVariables:
            assert f"<code>{var.name}</code>" in html, f"documentation misses {var.name}"
        # Sources: the build description, every file it lists, and Eigen.
        assert "sources/buildDescription.xml" in names
        build = ET.fromstring(z.read("sources/buildDescription.xml"))
        configs = build.findall("BuildConfiguration")
        assert [c.get("modelIdentifier") for c in configs] == [name]
        files = [f.get("name") for f in build.iter("SourceFile")]
        assert files and all(f"sources/{f}" in names for f in files), files
        assert "sources/Eigen/Dense" in names and "sources/Eigen/Core" in names
        assert any(n.startswith("sources/Eigen/src/") for n in names)
        # The modelDescription's FMI 2.0 <SourceFiles> agree with the build description.
        assert md.buildConfigurations and md.buildConfigurations[0].sourceFileSets[0].sourceFiles == files
        # Every header a shipped source includes with quotes is shipped too.
        shipped = {n[len("sources/"):] for n in names if n.startswith("sources/")}
        for f in shipped:
            if f.endswith((".cpp", ".h")) and not f.startswith("Eigen/"):
                text = z.read(f"sources/{f}").decode("utf-8")
                for inc in re.findall(r'#include "([^"]+)"', text):
                    here = str(Path(f).parent / inc)
                    assert inc in shipped or here in shipped or inc.startswith("fmi2"), f"{f}: {inc} not shipped"


def test_guids_differ_and_match_binary(fmu, make_slave):
    name, _, md = fmu
    other = fmpy.read_model_description(str(fmu_path(JOINT if name == ESTIMATOR else ESTIMATOR)))
    assert md.guid != other.guid
    assert re.fullmatch(r"\{[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}\}", md.guid)
    s = make_slave(name)  # instantiates with the modelDescription's GUID: the binary accepts it
    assert s.slave.component


def test_binary_reports_fmi_2_0_default_types(fmu, make_slave):
    name, _, _ = fmu
    s = make_slave(name)
    assert s.slave.getVersion() == "2.0"
    assert s.slave.getTypesPlatform() == "default"


def _parse_parameter_table_def(path: Path):
    rows = {}
    pattern = re.compile(r'^HDJ_PARAMETER\(\s*(\w+),\s*"([^"]*)",\s*([^,]+),\s*([^,]+),\s*([^,]+),\s*(\w+),')
    for line in path.read_text().splitlines():
        m = pattern.match(line)
        if m:
            n, unit, d, lo, hi, scope = m.groups()
            rows[n] = (unit, float(d), float(lo), float(hi), scope.lower())
    return rows


def test_installed_table_matches_parameter_table_def():
    """The installed package (and so its FMUs) was built from the current parameter_table.def."""
    src = REPO / "src" / "hdjoint" / "parameter_table.def"
    if not src.is_file():
        pytest.skip("no source tree next to the tests")
    rows = _parse_parameter_table_def(src)
    table = parameters.table()
    assert list(rows) == list(table), "parameter order/names differ: reinstall the package (pip install .)"
    for n, (unit, d, lo, hi, scope) in rows.items():
        info = table[n]
        assert (info.unit, info.default, info.min, info.max, info.scope) == (unit, d, lo, hi, scope), n
