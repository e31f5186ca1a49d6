"""Shared fixtures: the simulated benchtop plane (six robots) and a client connected to it."""

import os
import sys

import pytest

import axon


@pytest.fixture
def benchtop():
    with axon.fps.SimulatedPlane("benchtop") as plane:
        yield plane


@pytest.fixture
def client(benchtop):
    with axon.fps.Client() as fps:
        fps.open(benchtop.layout)
        fps.discover()
        yield fps


@pytest.fixture
def cli():
    """The axon program of this build (ctest sets AXON_CLI)."""
    path = os.environ.get("AXON_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("AXON_CLI is not set (run through ctest)")
    return path


@pytest.fixture
def source_dir():
    return os.environ.get("AXON_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture
def python():
    return sys.executable
