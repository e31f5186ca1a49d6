"""axon.fps layouts and the planner; a plan from Python equals `axon fps plan`'s plan.json."""

import json
import os
import subprocess

import numpy as np
import pytest

import axon
from axon.fps import Layout


def test_the_shipped_layouts_load_with_their_robots_and_neighbours():
    bench = Layout.load("benchtop")
    assert len(bench) == 6
    robots = bench.robots
    assert robots.dtype.names[:3] == ("id", "x_mm", "y_mm")
    assert list(robots.id) == list(bench.ids)
    first = int(robots.id[0])
    assert first in bench
    assert all(n in bench for n in bench.neighbours(first))
    assert set(bench.adjacent(first)) <= set(bench.neighbours(first))
    assert "boss" in bench.fibres(first) or bench.fibres(first)
    default = Layout.load("default")
    assert len(default) == 500
    assert len(default.buses) == 24
    assert len(default.neighbours(int(default.robots.id[0]))) > 0


def test_a_generated_layout_has_the_asked_robots_and_reads_back_from_its_yaml(tmp_path):
    layout = Layout.generate(robots=498, name="small")
    assert len(layout) == 498 and layout.name == "small"
    path = tmp_path / "small.yaml"
    path.write_text(layout.to_yaml())
    again = Layout.load(str(path))
    assert np.allclose(again.robots.x_mm, layout.robots.x_mm, atol=1e-3)  # as written in the file


def test_unknown_robots_and_layouts_raise_their_types():
    bench = Layout.load("benchtop")
    with pytest.raises(KeyError):
        bench.neighbours(9999)
    with pytest.raises(axon.InvalidArgument):
        Layout.load("no-such-layout")


def test_a_plan_from_arrays_is_verified_and_ends_at_the_targets():
    layout = Layout.load("benchtop")
    target = axon.fps.random_poses(layout, seed=4)
    p = axon.fps.plan(layout, axon.fps.folded_poses(layout), target, seed=4)
    assert p.verified and p.not_reached == 0
    assert p.end.shape == (6, 2)
    assert np.allclose(p.end, target)
    assert np.allclose(p.start, axon.fps.folded_poses(layout))
    assert p.duration_s > 0 and p.min_clearance_mm > 0
    alpha, beta = p.trajectory(int(p.ids[0]))
    assert alpha.shape[1] == 2 and alpha[0, 1] == 0.0  # (degrees, seconds), the start at 0 s
    assert np.all(np.diff(alpha[:, 1]) > 0)


def test_targets_by_id_and_bad_targets():
    layout = Layout.load("benchtop")
    ids = [int(i) for i in layout.ids]
    p = axon.fps.plan(layout, "folded", {ids[0]: (90.0, 150.0)})
    assert p.verified
    assert tuple(p.end[0]) == pytest.approx((90.0, 150.0))
    with pytest.raises(axon.fps.BadTarget):
        axon.fps.plan(layout, "folded", {9999: (90.0, 150.0)})
    with pytest.raises(axon.InvalidArgument):
        axon.fps.plan(layout, "folded", np.zeros((3, 2)))


def _without_timings(doc):
    doc = dict(doc)
    doc.pop("stats")
    return doc


@pytest.mark.parametrize("seed", [3])
def test_planning_500_robots_gives_the_plan_json_of_the_cli(cli, source_dir, tmp_path, seed):
    # One layout file for both (the CLI's `default` is this file, the library's is generated: their
    # positions differ in the last digits, and so would the plans).
    layout = os.path.join(source_dir, "data", "layouts", "default.yaml")
    out = tmp_path / "plan.json"
    subprocess.run([cli, "fps", "plan", "--layout", layout, "--from", "random", "--to", "random",
                    "--seed", str(seed), "-o", str(out)], check=True, capture_output=True)
    from_cli = json.loads(out.read_text())
    p = axon.fps.plan(Layout.load(layout), "random", "random", seed=seed)
    from_python = json.loads(p.to_json())
    assert len(from_python["robots"]) == 500
    assert _without_timings(from_python) == _without_timings(from_cli)
    assert p.verified == from_cli["verified"]
    assert p.duration_s == from_cli["duration_s"]
