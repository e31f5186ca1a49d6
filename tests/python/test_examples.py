"""The Python examples run to their own check (exit 0)."""

import os
import subprocess
import sys

import pytest

EXAMPLES = os.path.join(os.environ.get("AXON_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")),
                        "examples", "python")


@pytest.mark.parametrize("name", sorted(f for f in os.listdir(EXAMPLES) if f.endswith(".py")))
def test_example_runs_and_its_check_holds(name):
    result = subprocess.run([sys.executable, os.path.join(EXAMPLES, name)], capture_output=True, text=True,
                            timeout=240)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "check:" in result.stdout
