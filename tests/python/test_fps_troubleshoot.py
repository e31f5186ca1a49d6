"""axon.fps troubleshooting (interface document 9.4.2 and 9.4.3) against the simulated benchtop plane."""

import csv

import pytest

import axon


@pytest.fixture
def slow_plane():
    # Slower than the default x10: several current readings during the shortest test move.
    with axon.fps.SimulatedPlane("benchtop", time_scale=5.0, plc=False) as plane:
        yield plane


@pytest.fixture
def fps(slow_plane):
    with axon.fps.Client(poll_interval_s=0.02, discover_window_s=0.3) as client:
        client.open(slow_plane.layout)
        client.discover()
        yield client


def test_the_friction_trend_finds_a_stiffer_arm_against_its_history(fps, slow_plane, tmp_path):
    history = str(tmp_path / "friction.csv")
    first = fps.friction_survey([1], speeds_rpm=[1000, 2000, 3000], history_file=history)
    assert [a.verdict for a in first.arms] == ["baseline", "baseline"], first.summary
    fit = first.arms[0].fit
    assert fit.stiction_percent == pytest.approx(15, abs=1.5)
    assert fit.viscous_percent_per_krpm == pytest.approx(5, abs=0.6)
    assert all(p.readings > 0 for p in first.arms[0].points)
    slow_plane.set_friction_fault(1, "beta", 10)
    second = fps.friction_survey([1], speeds_rpm=[1000, 2000, 3000], history_file=history)
    verdicts = {a.arm: a for a in second.arms}
    assert verdicts["alpha"].verdict == "ok", second.summary
    assert verdicts["beta"].verdict == "increased" and verdicts["beta"].growth > 0.4, second.summary
    assert not second and "collision margin" in verdicts["beta"].advice
    with open(history) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and {r["arm"] for r in rows} == {"alpha", "beta"}


def test_the_hall_test_finds_a_stuck_sensor_and_restores_closed_loop(fps, slow_plane):
    slow_plane.set_hall_fault(2, "beta", "stuck")
    report = fps.hall_test(2)
    by_arm = {a.arm: a for a in report.arms}
    assert by_arm["alpha"].verdict == "ok" and by_arm["alpha"].tracking_error_deg <= 0.04, report.summary
    assert by_arm["beta"].verdict == "no_hall_change", report.summary
    assert all(a.restored for a in report.arms) and not report
    with pytest.raises(axon.InvalidArgument):
        slow_plane.set_hall_fault(2, "gamma", "stuck")


def test_troubleshooting_is_refused_while_locked(fps, slow_plane):
    fps.emergency_stop("operator")
    with pytest.raises(axon.fps.MotionLocked):
        fps.hall_test(1)

