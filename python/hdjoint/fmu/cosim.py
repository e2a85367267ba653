"""The joint-torque-feedback system (systems/*.ssd) run by independent
co-simulation masters: fmpy, libcosim (libcosimpy; SSP and OSP), ecos
(ecospy) and INTO-CPS Maestro (its jar).

Every runner returns `Trajectories`: the outputs of the system's FMUs
sampled after each communication step, on the time grid k*h (the end of the
step that produced them), so runs of different masters can be compared row
by row. All masters here exchange values after every FMU has stepped
(Jacobi): an output computed in the step [t, t+h) is an input of the others
in [t+h, t+2h). Masters differ in how they label rows (the start or the end
of the step) and in what an input holds before the first exchange; each
runner maps its master's convention onto the common grid.

The external masters can abort the process on models they dislike, so
`run_in_subprocess` runs one in a child Python (`python -m hdjoint.fmu.cosim`).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hdjoint.fmu.shipped import shipped_file

SYSTEMS = ("JointTorqueFeedback", "JointTorqueFeedbackSensor", "JointTorqueFeedbackHat")
MASTERS = ("fmpy", "libcosim-ssp", "libcosim-osp", "ecos", "maestro")
_SYSTEM_DIR = Path(__file__).parents[1] / "systems"  # installed beside the package's top
_SSD_NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}

# What the comparisons and the JTF result look at (component.variable).
SIGNALS = (
    "joint.theta_l", "joint.theta_m", "joint.tau_joint", "joint.omega_link",
    "controller.i_m", "controller.tau_d", "controller.theta_ref", "controller.tau_ext", "controller.e_link",
    "estimator.tau_ukf", "estimator.tau_compliance",
)


def ssp_path(name: str = "JointTorqueFeedback") -> Path:
    """Path of a shipped SSP archive (SystemStructure.ssd + resources/*.fmu)."""
    return shipped_file(_SYSTEM_DIR, name, SYSTEMS, ".ssp", "system")


def osp_structure_path() -> Path:
    """The shipped OspSystemStructure.xml (the JointTorqueFeedback system for libcosim)."""
    return _SYSTEM_DIR / "OspSystemStructure.xml"


@dataclass
class System:
    """Components (name -> FMU file inside the SSP) and connections of an SSD."""
    components: dict[str, str]
    connections: list[tuple[str, str, str, str]]  # (start element, start connector, end element, end connector)
    connectors: dict[str, list[tuple[str, str]]]   # component -> [(name, kind)]


def read_system(ssp: str | Path) -> System:
    """Reads SystemStructure.ssd from an SSP archive (the subset the systems use)."""
    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    components, connectors = {}, {}
    for c in root.iter(f"{{{_SSD_NS['ssd']}}}Component"):
        components[c.get("name")] = c.get("source")
        connectors[c.get("name")] = [(k.get("name"), k.get("kind"))
                                     for k in c.iter(f"{{{_SSD_NS['ssd']}}}Connector")]
    connections = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
                   for c in root.iter(f"{{{_SSD_NS['ssd']}}}Connection")]
    return System(components, connections, connectors)


@dataclass
class Trajectories:
    master: str
    time: np.ndarray                 # s, the end of each communication step: h, 2h, ..., n*h
    values: dict[str, np.ndarray]    # "component.variable" -> value after that step

    def __getitem__(self, key: str) -> np.ndarray:
        return self.values[key]

    def save(self, path: str | Path) -> None:
        np.savez(path, time=self.time, master=self.master, **self.values)

    @classmethod
    def load(cls, path: str | Path) -> "Trajectories":
        with np.load(path) as d:
            values = {k: d[k] for k in d.files if k not in ("time", "master")}
            return cls(str(d["master"]), d["time"], values)


def _steps(stop_time: float, step: float) -> int:
    n = int(round(stop_time / step))
    if n < 1 or abs(n * step - stop_time) > 1e-9 * max(1.0, stop_time):
        raise ValueError(f"stop time {stop_time} is not a whole number of steps of {step}")
    return n


def _grid(n: int, step: float) -> np.ndarray:
    return np.arange(1, n + 1) * step


# ---- fmpy ---------------------------------------------------------------------------------

def run_fmpy(ssp: str | Path, stop_time: float, step: float, parameters: dict[str, float] | None = None
             ) -> Trajectories:
    """fmpy.ssp.simulate_ssp. Its rows are labelled with the start of the step
    whose results they hold; relabelled to the end. `parameters` maps
    "component.variable" to a start value (fmpy's ParameterSet)."""
    from fmpy.ssp.simulation import simulate_ssp
    parameter_set = None
    if parameters:
        from fmpy.ssp.ssd import Parameter, ParameterSet
        parameter_set = ParameterSet(name="hdjoint")
        parameter_set.parameters = []
        for name, value in parameters.items():
            p = Parameter(name=name)
            p.type, p.value = "Real", float(value)
            parameter_set.parameters.append(p)
    n = _steps(stop_time, step)
    # simulate_ssp accumulates time += step; stop half a step early so that
    # round-off never adds an (n+1)-th step.
    result = simulate_ssp(str(ssp), start_time=0.0, stop_time=(n - 0.5) * step, step_size=step,
                          parameter_set=parameter_set)
    if len(result) != n:
        raise RuntimeError(f"fmpy made {len(result)} steps, expected {n}")
    values = {name: np.asarray(result[name], dtype=float) for name in result.dtype.names if name != "time"}
    return Trajectories("fmpy", _grid(n, step), values)


# ---- libcosim -------------------------------------------------------------------------------

def run_libcosim(source: str | Path, stop_time: float, step: float, kind: str = "ssp",
                 parameters: dict[str, float] | None = None) -> Trajectories:
    """libcosim through libcosimpy, from the SSP (unpacked; libcosim reads
    the .ssd next to its resources) or from an OspSystemStructure.xml.
    Values are read after every step (last-value observer)."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    ns = int(round(step * 1e9))
    if kind == "ssp":
        execution = CosimExecution.from_ssp_file(str(source), step_size=ns)
    elif kind == "osp":
        execution = CosimExecution.from_osp_config_file(str(source))
    else:
        raise ValueError(f"kind must be 'ssp' or 'osp', not {kind!r}")
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs, everything = {}, {}
    for info in execution.slave_infos():
        slave = info.name.decode()
        index = info.index
        for v in execution.slave_variables(index):
            name = f"{slave}.{v.name.decode()}"
            everything[name] = (index, v.reference)
            if name in SIGNALS:
                refs[name] = (index, v.reference)
    for name, value in (parameters or {}).items():
        if name not in everything or not execution.real_initial_value(*everything[name], float(value)):
            raise ValueError(f"libcosim cannot set {name}")
    n = _steps(stop_time, step)
    out = {name: np.empty(n) for name in refs}
    for k in range(n):
        if not execution.step():
            raise RuntimeError(f"libcosim failed at step {k}")
        for name, (index, vr) in refs.items():
            out[name][k] = observer.last_real_values(index, [vr])[0]
    return Trajectories(f"libcosim-{kind}", _grid(n, step), out)


# ---- ecos ----------------------------------------------------------------------------------------

def run_ecos(ssp: str | Path, stop_time: float, step: float, parameters: dict[str, float] | None = None
             ) -> Trajectories:
    """ecos through ecospy, from the SSP; values read after every step."""
    from ecospy import EcosSimulation
    system = read_system(ssp)
    names = [s for s in SIGNALS if s.split(".")[0] in system.components]
    n = _steps(stop_time, step)
    out = {name: np.empty(n) for name in names}
    with EcosSimulation(ssp_path=str(ssp), step_size=step) as sim:
        for name, value in (parameters or {}).items():
            component, variable = name.split(".", 1)
            sim.set_real(f"{component}::{variable}", float(value))
        if not sim.init():
            raise RuntimeError("ecos failed to initialise the system")
        for k in range(n):
            sim.step()
            for name in names:
                component, variable = name.split(".", 1)
                out[name][k] = sim.get_real(f"{component}::{variable}")
        sim.terminate()
    return Trajectories("ecos", _grid(n, step), out)


# ---- INTO-CPS Maestro --------------------------------------------------------------------------

def maestro_config(ssp: str | Path, fmu_dir: Path, stop_time: float, step: float,
                   parameters: dict[str, float] | None = None) -> dict:
    """Maestro's sg1 (multi-model + co-simulation) configuration of the SSP's
    system: the same FMUs and connections, read from the .ssd."""
    system = read_system(ssp)
    fmus = {f"{{{c}}}": (fmu_dir / Path(src).name).resolve().as_uri() for c, src in system.components.items()}
    connections: dict[str, list[str]] = {}
    for a, b, c, d in system.connections:
        connections.setdefault(f"{{{a}}}.{a}.{b}", []).append(f"{{{c}}}.{c}.{d}")
    log: dict[str, list[str]] = {}
    for name in SIGNALS:
        component, variable = name.split(".", 1)
        if component in system.components:
            log.setdefault(f"{{{component}}}.{component}", []).append(variable)
    values = {}
    for name, value in (parameters or {}).items():
        component, variable = name.split(".", 1)
        values[f"{{{component}}}.{component}.{variable}"] = float(value)
    return {"fmus": fmus, "connections": connections, "logVariables": log, "parameters": values,
            "algorithm": {"type": "fixed-step", "size": step}, "startTime": 0.0, "endTime": stop_time,
            "loggingOn": False}


def run_maestro(ssp: str | Path, stop_time: float, step: float, jar: str | Path, timeout: float = 600.0,
                parameters: dict[str, float] | None = None) -> Trajectories:
    """INTO-CPS Maestro 3 (`import sg1 --interpret`). Its outputs.csv has a
    row at the start time (initial values) and one after every step."""
    import csv
    n = _steps(stop_time, step)
    with tempfile.TemporaryDirectory(prefix="hdjoint-maestro-") as tmp:
        work = Path(tmp)
        with zipfile.ZipFile(ssp) as z:
            z.extractall(work / "ssp")
        config = maestro_config(ssp, work / "ssp" / "resources", stop_time, step, parameters)
        (work / "config.json").write_text(json.dumps(config, indent=1))
        proc = subprocess.run(["java", "-jar", str(jar), "import", "sg1", str(work / "config.json"),
                               f"-output={work / 'out'}", "--interpret"],
                              cwd=work, capture_output=True, text=True, timeout=timeout)
        results = work / "out" / "outputs.csv"
        if proc.returncode != 0 or not results.is_file():
            raise RuntimeError(f"maestro failed ({proc.returncode}): {proc.stdout[-2000:]}{proc.stderr[-2000:]}")
        with open(results, newline="") as f:
            rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    time = data[:, 0]
    # Keep the rows after each step: times k*h for k = 1..n.
    index = np.rint(time / step).astype(int)
    keep = np.searchsorted(index, np.arange(1, n + 1))
    if keep.max(initial=0) >= len(index) or not np.array_equal(index[keep], np.arange(1, n + 1)):
        raise RuntimeError(f"maestro's outputs.csv does not hold every step of {step} s up to {stop_time} s")
    out = {}
    for j, column in enumerate(header):
        # "{joint}.joint.theta_l" -> "joint.theta_l"
        parts = column.split(".")
        if len(parts) >= 3 and parts[0].startswith("{"):
            name = ".".join(parts[1:])
            if name in SIGNALS:
                out[name] = data[keep, j]
    return Trajectories("maestro", _grid(n, step), out)


# ---- running a master in a child process ------------------------------------------------------------

def maestro_jar() -> Path | None:
    """The Maestro jar that scripts/install_cosim.sh fetched, if any ($HDJOINT_MAESTRO_JAR overrides)."""
    env = os.environ.get("HDJOINT_MAESTRO_JAR")
    if env:
        return Path(env)
    for base in (Path.cwd(), Path(__file__).resolve().parents[3]):
        jar = base / "build" / "cosim-tools" / "maestro-3.1.1-jar-with-dependencies.jar"
        if jar.is_file():
            return jar
    return None


def run(master: str, system: str, stop_time: float, step: float, parameters: dict[str, float] | None = None
        ) -> Trajectories:
    """One master on a shipped system (in this process); `parameters` maps
    "component.variable" to a start value, set through the master's own API."""
    ssp = ssp_path(system)
    if master == "fmpy":
        return run_fmpy(ssp, stop_time, step, parameters)
    if master == "ecos":
        return run_ecos(ssp, stop_time, step, parameters)
    if master == "maestro":
        jar = maestro_jar()
        if jar is None:
            raise FileNotFoundError("the Maestro jar is missing: run scripts/install_cosim.sh")
        return run_maestro(ssp, stop_time, step, jar, parameters=parameters)
    if master in ("libcosim-ssp", "libcosim-osp"):
        with tempfile.TemporaryDirectory(prefix="hdjoint-libcosim-") as tmp:
            work = Path(tmp)
            with zipfile.ZipFile(ssp) as z:
                z.extractall(work)
            if master == "libcosim-ssp":
                return run_libcosim(work, stop_time, step, "ssp", parameters)
            if system != "JointTorqueFeedback":
                raise ValueError("the OSP structure describes the JointTorqueFeedback system only")
            for fmu in (work / "resources").glob("*.fmu"):
                shutil.copy(fmu, work / fmu.name)
            shutil.copy(osp_structure_path(), work / "OspSystemStructure.xml")
            return run_libcosim(work / "OspSystemStructure.xml", stop_time, step, "osp", parameters)
    raise ValueError(f"unknown master '{master}'; known: {', '.join(MASTERS)}")


def run_in_subprocess(master: str, system: str, stop_time: float, step: float, timeout: float = 600.0,
                      cpu: int | None = None, parameters: dict[str, float] | None = None) -> Trajectories:
    """`run` in a child Python, so a master that aborts cannot take the caller
    down; `cpu` pins the child to one core (for timing)."""
    with tempfile.TemporaryDirectory(prefix="hdjoint-master-") as tmp:
        out = Path(tmp) / "result.npz"
        cmd = [sys.executable, "-m", "hdjoint.fmu.cosim", master, system, str(stop_time), str(step), str(out),
               json.dumps(parameters or {})]
        if cpu is not None and shutil.which("taskset"):
            cmd = ["taskset", "-c", str(cpu)] + cmd
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        if proc.returncode != 0 or not out.is_file():
            raise RuntimeError(f"{master} failed with exit code {proc.returncode}:\n{proc.stdout[-3000:]}\n"
                               f"{proc.stderr[-3000:]}")
        return Trajectories.load(out)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) not in (5, 6):
        print("usage: python -m hdjoint.fmu.cosim MASTER SYSTEM STOP_TIME STEP OUT.npz [PARAMETERS_JSON]",
              file=sys.stderr)
        return 2
    master, system, stop_time, step, out = args[:5]
    parameters = json.loads(args[5]) if len(args) == 6 else None
    run(master, system, float(stop_time), float(step), parameters).save(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
