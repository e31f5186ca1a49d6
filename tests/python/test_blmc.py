"""axon.blmc against the board simulated in this process: a Python front end to the 1 kHz loop,
the idle action, the safety clamp, typed errors and Ctrl-C."""

import math
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import axon

# A loaded machine (two cores, several builds) holds threads longer than a real board's timing
# allows: the board's receive timeout and the host's stale-data limit get slack here (as in the
# C++ tests); the front end's own stale bound is the one under test.
SLACK = dict(stale_data_s=0.5, max_velocity_krpm=100.0)
LIMIT_A = 0.5


def wait_until(condition, limit_s=5.0):
    end = time.monotonic() + limit_s
    while not condition() and time.monotonic() < end:
        time.sleep(0.005)
    return condition()


def motors_off(sim):
    r = sim.report()
    return not r.status.system_enabled and r.motor_enabled == [False, False] and list(r.iq_ref_a) == [0.0, 0.0]


@pytest.fixture
def sim():
    with axon.blmc.SimulatedBoard(alignment_time_s=0.2) as s:
        yield s


@pytest.fixture
def board(sim):
    with axon.blmc.MotorBoard(sim.bus_spec, recv_timeout_ms=500) as b:
        b.enable()
        yield b


def test_a_python_front_end_at_100_hz_drives_the_1_khz_loop_clamped_then_idle(sim, board):
    board.start(max_current_a=LIMIT_A, stale_after_s=0.1, first_action_timeout_s=5.0, **SLACK)
    sent, seen_iq = 0, []
    end = time.monotonic() + 2.0
    while time.monotonic() < end:  # the front end: 100 Hz, asking for twice the limit on motor 1
        board.set_currents([2 * LIMIT_A, -0.25])
        sent += 1
        seen_iq.append(sim.report().iq_ref_a)
        time.sleep(0.01)
    applied = board.applied
    assert applied.source == "action" and not applied.idle
    assert list(applied.current_a) == [2 * LIMIT_A, -0.25]  # the action itself; the clamp comes after the law
    seen_iq = np.array(seen_iq)
    assert seen_iq[:, 0].max() == LIMIT_A  # what reached the board: clamped
    assert seen_iq[:, 1].min() == -0.25  # within the limit: as asked
    assert isinstance(board.state.position_rev, np.ndarray) and board.state.position_rev.shape == (2,)

    # The front end stops: after stale_after_s the back end applies zero current, and says so.
    assert wait_until(lambda: board.applied.source == "stale")
    assert wait_until(lambda: list(sim.report().iq_ref_a) == [0.0, 0.0])
    assert board.applied.idle and list(board.applied.current_a) == [0.0, 0.0]
    report = board.stop()
    print(report, report.actions)  # the loop's own counts (overruns among them) for the log
    assert report.end == "requested" and report.fault is None, report.fault_text
    assert report.cycles == report.stats.cycles == report.actions.cycles  # the back end ran every cycle
    assert report.overruns == report.stats.overruns <= report.cycles
    assert 0 < report.actions.actions <= sent
    # At least the one after the end (a loaded machine may stall the script for 100 ms before).
    assert report.actions.stale_episodes >= 1 and report.actions.stale_cycles > 0
    assert report.actions.idle_cycles >= report.actions.stale_cycles
    assert 0 <= report.actions.first_action_s < 5.0
    assert "ControlReport(end='requested'" in repr(report)
    assert board.enabled  # a requested end leaves the motors on, at zero current


def test_the_loops_figures_are_read_while_it_runs_and_agree_with_the_report(board):
    assert board.loop.cycles == 0 and not board.loop.running  # before any run
    board.start(max_current_a=LIMIT_A, first_action_timeout_s=5.0, **SLACK)
    board.set_currents([0.1, 0.0])
    assert wait_until(lambda: board.loop.cycles >= 300)  # about 0.3 s at 1 kHz, counted from Python
    live = board.loop
    assert live.running and live.period_max_s > 0 and live.overruns <= live.cycles
    report = board.stop()
    done = board.loop
    assert not done.running and done.cycles >= live.cycles
    # The drained records are the report's cycles (the loop's last ones drained at the stop).
    assert report.cycles - 5 <= done.cycles <= report.cycles
    assert done.overruns <= report.overruns
    assert done.jitter_max_s <= report.stats.jitter_max_s + 1e-6
    assert "LoopFigures(cycles=" in repr(done)


def test_pd_targets_and_gains_reach_the_back_end(board):
    board.start(**SLACK)
    start = board.state.position_rev
    board.set_pd(start + [0.1, -0.1], (8.0, 0.1), velocities_rev_s=[0.0, 0.0])
    assert wait_until(lambda: board.applied.action == 1 and board.applied.source == "action")
    m1, m2 = board.applied.command
    assert (m1.kp, m1.kd, m2.kp) == (8.0, 0.1, 8.0)
    assert m1.position_rev == pytest.approx(start[0] + 0.1) and m2.position_rev == pytest.approx(start[1] - 0.1)
    board.set_pd([0.0, 0.0], [[1.0, 0.0], [2.0, 0.5]])  # per-motor gains
    assert wait_until(lambda: board.applied.action == 2)
    assert board.applied.command[1].kd == 0.5
    assert board.stop().fault is None


def test_no_first_action_in_time_ends_the_run_with_the_motors_disabled(sim, board):
    board.start(first_action_timeout_s=0.2, **SLACK)
    assert wait_until(lambda: not board.running)
    report = board.stop()
    assert report.end == "no_first_action"
    assert report.actions.actions == 0 and report.actions.idle_cycles == report.cycles
    assert board.applied.source == "gave_up"
    assert not board.enabled
    assert wait_until(lambda: motors_off(sim))


def test_a_board_fault_is_a_reported_safety_stop(sim, board):
    board.start(**SLACK)
    board.set_currents([0.1, 0.1])
    sim.inject("encoder")
    assert wait_until(lambda: not board.running, limit_s=10)
    report = board.stop()
    assert report.end == "fault" and report.fault is not None  # seen first as stale data or as the error code
    assert "ENCODER" in report.fault_text, report.fault_text  # either way named by the board's next status


def test_bad_input_raises_typed_errors(sim, board):
    with pytest.raises(axon.blmc.NotRunning):
        board.set_currents([0.1, 0.0])
    with pytest.raises(axon.blmc.InvalidArgument) as e:
        board.start(max_current_a=-1.0)
    assert isinstance(e.value, ValueError) and e.value.category == "axon.blmc.host"
    with pytest.raises(axon.InvalidArgument):
        board.start(stale_after_s=0.0)
    board.start(**SLACK)
    for bad in ([math.nan, 0.0], [1.0, 2.0, 3.0], "two", [[1.0, 2.0]]):
        with pytest.raises(axon.blmc.InvalidArgument):
            board.set_currents(bad)
    with pytest.raises(axon.blmc.InvalidArgument, match="gains must be >= 0"):
        board.set_pd([0.0, 0.0], (-1.0, 0.0))
    with pytest.raises(axon.blmc.InvalidArgument):
        board.set_pd([0.0, 0.0], (1.0, 2.0, 3.0))
    with pytest.raises(axon.blmc.ControlRunning):
        board.start(**SLACK)
    with pytest.raises(axon.blmc.ControlRunning):
        board.set_onboard_gains((1.0, 1.0), (0.0, 0.0))
    board.stop()
    with pytest.raises(axon.blmc.InvalidArgument):
        board.set_onboard_gains((-1.0, 1.0), (0.0, 0.0))
    board.set_onboard_current_limits((0.0, 0.0), (0.0, 0.0))
    board.disable()
    with pytest.raises(axon.blmc.NotEnabled):
        board.start()
    with pytest.raises(axon.blmc.InvalidArgument):
        sim.inject("meteor")
    with pytest.raises(axon.can.ParseError):
        axon.blmc.MotorBoard("nonsense")
    assert issubclass(axon.blmc.Timeout, axon.TimeoutError) and issubclass(axon.blmc.Error, axon.Error)


def test_ctrl_c_during_run_control_leaves_the_motors_disabled(sim, board):
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        board.run_control(30.0, first_action_timeout_s=30.0, **SLACK)
    assert time.monotonic() - started < 10  # not the 30 s
    assert not board.enabled and not board.running
    assert wait_until(lambda: motors_off(sim))


def test_home_finds_each_motors_index_mark_where_the_simulator_put_it():
    marks = (0.3, 0.7)
    with axon.blmc.SimulatedBoard(alignment_time_s=0.2, index_offset_rev=marks) as sim, \
            axon.blmc.MotorBoard(sim.bus_spec, recv_timeout_ms=500) as board:
        board.enable()
        report = board.home(speed_rev_s=0.5, max_travel_rev=1.2, timeout_s=10, stale_data_s=0.5)
        assert report.all_found, report
        assert report.control.fault is None, report.control.fault_text
        for motor, mark in zip(report.motors, marks):
            assert motor.state == "found", motor
            assert abs(motor.index_rev - mark) < 0.001, motor
        assert board.enabled and not board.running  # homing ends its run; the motors stay enabled


def test_home_that_finds_no_mark_within_its_travel_says_so_per_motor(sim, board):
    report = board.home(speed_rev_s=0.5, max_travel_rev=0.05, timeout_s=10, stale_data_s=0.5)
    assert not report.all_found
    assert [m.state for m in report.motors] == ["failed", "failed"], report
    with pytest.raises(axon.blmc.InvalidArgument):
        board.home(timeout_s=-1)


def test_home_before_enable_is_refused(sim):
    with axon.blmc.MotorBoard(sim.bus_spec) as board:
        with pytest.raises(axon.blmc.NotEnabled):
            board.home()


def test_the_docs_quick_start_runs(source_dir):
    text = open(os.path.join(source_dir, "docs", "python.md"), encoding="utf-8").read()
    section = text.split("## `axon.blmc`", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env)
    assert result.returncode == 0, result.stdout + result.stderr
