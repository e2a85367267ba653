"""The estimator FMU can be rebuilt from the sources it ships (sources/ with
Eigen and the build description), with fmpy's own build support, and the
rebuilt binary computes what the shipped one does.

Compiling takes ~15-30 s; it runs by default. Deselect with -m "not slow"."""
from __future__ import annotations

import hashlib
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu

from hdjoint.fmu.runner import run_estimator_fmu

from conftest import ESTIMATOR, ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS, Slave

pytestmark = pytest.mark.slow


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def rebuilt(tmp_path_factory, estimator_fmu):
    root = tmp_path_factory.mktemp("rebuild")
    unzipdir = Path(fmpy.extract(str(estimator_fmu), str(root / "fmu")))
    binary = unzipdir / "binaries" / fmpy.platform / f"{ESTIMATOR}.so"
    shipped_hash = sha256(binary)
    binary.unlink()  # nothing but the sources may produce the new one
    assert not any(unzipdir.rglob("*.o")) and not any(unzipdir.rglob("*.a"))
    build = root / "build"
    build.mkdir()
    mp = pytest.MonkeyPatch()
    mp.setenv("CMAKE_BUILD_PARALLEL_LEVEL", "4")
    try:
        build_platform_binary(unzipdir, build_dir=build)
    finally:
        mp.undo()
    assert binary.is_file(), "the build did not install the binary"
    fmu = root / f"{ESTIMATOR}.fmu"
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(unzipdir.rglob("*")):
            if f.is_file():
                z.write(f, f.relative_to(unzipdir).as_posix())
    return {"dir": unzipdir, "fmu": fmu, "binary": binary, "shipped_hash": shipped_hash}


def test_rebuilt_binary_is_new(rebuilt):
    assert sha256(rebuilt["binary"]) != rebuilt["shipped_hash"]


def test_rebuilt_fmu_is_valid(rebuilt):
    assert validate_fmu(str(rebuilt["fmu"])) == []


def test_rebuilt_fmu_gives_the_shipped_outputs(rebuilt, estimator_fmu, recording, estimator_params):
    r = recording.slice(0, 1500)
    shipped = run_estimator_fmu(r.time, r.i_m, r.theta_m, r.theta_l, estimator_params, fmu=estimator_fmu)
    again = run_estimator_fmu(r.time, r.i_m, r.theta_m, r.theta_l, estimator_params, fmu=rebuilt["fmu"])
    for name in ESTIMATOR_OUTPUTS:
        assert np.ptp(shipped[name]) > 0, name
        np.testing.assert_allclose(again[name], shipped[name], rtol=1e-12, atol=1e-12, err_msg=name)


def test_rebuilt_fmu_handles_errors_and_state_like_the_shipped_one(rebuilt, recording):
    s = Slave(rebuilt["dir"], "rebuilt")
    try:
        s.start(inputs={"i_m": 0.0, "theta_m": 0.0, "theta_l": 0.0})
        u = np.column_stack([recording.i_m, recording.theta_m, recording.theta_l])[:100]
        s.run(0.0, [1e-3] * 50, u[:50], ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS)
        blob = s.slave.serializeFMUstate(state := s.slave.getFMUstate())
        s.slave.freeFMUstate(state)
        first = s.run(0.05, [1e-3] * 50, u[50:], ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS)
        restored = s.slave.deSerializeFMUstate(blob)
        s.slave.setFMUstate(restored)
        s.slave.freeFMUstate(restored)
        assert np.array_equal(first, s.run(0.05, [1e-3] * 50, u[50:], ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS))
        with pytest.raises(Exception):
            s.set({"theta_m": float("nan")})
        assert "theta_m = nan is not finite" in s.errors()[-1]
    finally:
        s.free()
