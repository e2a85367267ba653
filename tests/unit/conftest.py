"""Fixtures of the command-line tests: one simulated recording per session."""
from __future__ import annotations

import shutil

import pytest

from hdjoint.cli import main


@pytest.fixture(scope="session")
def simulated(tmp_path_factory):
    """`hdjoint simulate --duration 2 -o rec.csv`, once per session."""
    d = tmp_path_factory.mktemp("sim")
    path = d / "rec.csv"
    assert main(["simulate", "--duration", "2", "-o", str(path)]) == 0
    return path


@pytest.fixture
def rec_csv(simulated, tmp_path):
    path = tmp_path / "rec.csv"
    shutil.copyfile(simulated, path)
    return path
