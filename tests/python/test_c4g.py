"""axon.c4g against the controller simulated in this process: a mode 4 trajectory given from numpy,
monitor and echo, the cycle statistics, bad arrays, a condition that ends the run, and Ctrl-C."""

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

PROGRAM = axon.c4g.open_program(4)  # drive on, mode 4 on arm 1, wait for the PC, 504
# For runs the PC ends early: the program ends the exchange as soon as the arm is back in mode 0,
# before the closed server's silence would count as a communication error.
SHORT = axon.c4g.open_program(4, delay_s=0)


def raised_cosine(seconds, period_s, target_deg):
    """(rows, 6): one row a cycle from 0 to target_deg (six axes), eased in and out."""
    s = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0.0, 1.0, int(round(seconds / period_s)) + 1))
    return np.outer(s, np.asarray(target_deg, dtype=float))


def serve(app, program, **server_args):
    """Runs a session against a simulated six-axis controller (lenient reply window: a loaded test
    machine); returns (the server's report, the controller's report)."""
    with axon.c4g.Server(app, **server_args) as server, \
            axon.c4g.SimulatedController(server, program=program, reply_window="period") as controller:
        report = server.run()
        return report, controller.wait(timeout_s=30)


def assert_every_cycle_answered(report, seen):
    """Every packet the controller sent reached the server, which answers each one; the controller
    counted the answers that came late (misses), never ten in a row (a communication error)."""
    assert seen.outcome == "completed", seen.outcome_text
    assert report.stats.packets == seen.stats.packets_sent
    assert seen.stats.replies_ok > 0 and seen.stats.max_consecutive_misses < 10
    assert report.stats.safety_fault == "none" and report.stats.protocol_errors == 0


def assert_answered_until_the_server_closed(report, seen):
    """A run the PC ended early: the server closes once the arm is back in mode 0, and the program's
    last packet (504) may find it closed; the controller counts what went unanswered."""
    assert seen.outcome == "completed", seen.outcome_text
    assert seen.stats.packets_sent - report.stats.packets <= seen.stats.misses
    assert seen.stats.max_consecutive_misses < 10
    assert report.stats.safety_fault == "none" and report.stats.protocol_errors == 0


def test_a_2s_mode4_trajectory_from_numpy_is_followed():
    target = [10.0, -5.0, 5.0, 0.0, 0.0, 0.0]
    positions = raised_cosine(2.0, 0.002, target)  # the six-axis robot's period is 2 ms: 1001 rows
    app = axon.c4g.Stream(positions)               # absolute: the simulated arm starts at 0 deg
    report, seen = serve(app, PROGRAM, until_controller_ends=True, verify_reply_fields=True)

    assert report.finished and report.ok, report.text()
    assert app.rows == len(positions) and app.progress >= len(positions) - 1
    assert_every_cycle_answered(report, seen)
    assert report.stats.cyclic_packets > len(positions)
    timing = report.stats.timing
    assert timing.nominal_period_s == pytest.approx(0.002)
    assert 0 < timing.cycle_time_p50_s <= timing.cycle_time_max_s
    np.testing.assert_allclose(seen.joints_deg(1), positions[-1], atol=0.05)


def test_a_trajectory_sampled_from_rows_dt_s_apart():
    positions = raised_cosine(0.5, 0.05, [0.0, 3.0, 0.0, 0.0, 0.0, 0.0])  # 11 rows, 50 ms apart
    app = axon.c4g.Stream(positions, dt_s=0.05, relative=True)
    report, seen = serve(app, PROGRAM, until_controller_ends=True)
    assert report.finished, report.text()
    assert app.rows == 251  # 0.5 s at 2 ms, both ends
    assert_every_cycle_answered(report, seen)
    np.testing.assert_allclose(seen.joints_deg(1), positions[-1], atol=0.05)


def test_monitor_answers_every_packet_until_the_program_ends():
    app = axon.c4g.Monitor()
    report, seen = serve(app, "steps:\n  - drive_on\n  - delay: 0.3\n  - exit_open\n")
    assert report.reason == "controller ended the exchange (504)"
    assert_every_cycle_answered(report, seen)
    assert app.drives_on_cycles > 100  # 0.3 s at 2 ms
    assert report.ok and not report.finished and app.error is None


def test_echo_returns_the_targets_in_mode_0_prime():
    app = axon.c4g.Echo()
    program = """steps:
  - drive_on
  - go_open: {type: B, mode: "0'", arms: [1]}
  - move: {arm: 1, deg: [3, 0, 0, 0, 0, 0], duration: 0.3}
  - go_open: {type: A, mode: 0, arms: [1]}
  - exit_open
"""
    report, seen = serve(app, program)
    assert_every_cycle_answered(report, seen)
    assert app.echoed > 100
    np.testing.assert_allclose(seen.joints_deg(1)[0], 3.0, atol=0.05)


@pytest.mark.parametrize("bad", [
    np.zeros(6),                          # 1-D
    np.zeros((2, 3, 6)),                  # 3-D
    np.zeros((0, 6)),                     # no rows
    np.zeros((5, 0)),                     # no axes
    np.array([["0", "1"], ["2", "3"]]),   # strings
    np.zeros((3, 6), dtype=complex),
    [[0.0, float("nan")]],                # not finite
    "trajectory.csv",
])
def test_a_bad_array_is_an_invalid_argument(bad):
    with pytest.raises(axon.InvalidArgument) as raised:
        axon.c4g.Stream(bad)
    assert isinstance(raised.value, ValueError) and "positions_deg" in str(raised.value)


def test_other_array_types_and_bad_settings():
    assert axon.c4g.Stream([[0, 0, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0]]).name == "stream"  # nested lists, integers
    assert axon.c4g.Stream(np.zeros((4, 6), dtype=np.float32)[:, ::2].T).name == "stream"  # non-contiguous
    with pytest.raises(axon.InvalidArgument, match="mode"):
        axon.c4g.Stream(np.zeros((2, 6)), mode=7)
    with pytest.raises(axon.InvalidArgument, match="dt_s|step"):
        axon.c4g.Stream(np.zeros((2, 6)), dt_s=0.0)
    with pytest.raises(axon.InvalidArgument):
        axon.c4g.SimulatedController("127.0.0.1:1", reply_window="sometimes")


def test_the_wrong_axis_count_is_refused_before_anything_moves():
    app = axon.c4g.Stream(np.zeros((10, 7)))  # the arm has six axes
    report, seen = serve(app, PROGRAM)
    assert report.reason == "application error" and report.exit_code == 1
    assert "7 axes" in app.error and report.error == app.error
    np.testing.assert_allclose(seen.joints_deg(1), 0.0, atol=1e-6)


def test_a_port_in_use_is_a_connection_error():
    with axon.c4g.Server(axon.c4g.Monitor()) as first:
        assert first.port > 0 and first.address.endswith(f":{first.port}")
        with pytest.raises(axon.ConnectionError):
            axon.c4g.Server(axon.c4g.Monitor(), listen=first.address)


def test_a_condition_ends_the_run_cleanly():
    positions = raised_cosine(20.0, 0.002, [10.0, 0, 0, 0, 0, 0])
    app = axon.c4g.Stream(positions)
    with axon.c4g.Server(app) as server, \
            axon.c4g.SimulatedController(server, program=SHORT, reply_window="period") as controller:
        report = server.run(until=lambda: app.progress > 250)  # 0.5 s into a 20 s trajectory
        seen = controller.wait(timeout_s=30)
    assert report.reason == "stopped"  # the app slowed to rest and left mode 4: it counts as done
    assert_answered_until_the_server_closed(report, seen)
    assert 0.0 < seen.joints_deg(1)[0] < 1.0  # stopped early, along the path


def test_live_stats_count_up_while_the_server_runs():
    app = axon.c4g.Monitor()
    seen = []

    def sample():  # run()'s condition, between polls, off the cycle thread
        seen.append(server.stats.cyclic_packets)
        return False
    with axon.c4g.Server(app) as server, \
            axon.c4g.SimulatedController(server, program="steps:\n  - drive_on\n  - delay: 0.5\n  - exit_open\n",
                                         reply_window="period") as controller:
        assert server.stats.packets == 0  # bound, nothing came yet
        report = server.run(until=sample)
        controller.wait(timeout_s=30)
    live = [n for n in seen if n > 0]
    assert len(set(live)) >= 3, seen  # counting up during the run, not only at its end
    assert live == sorted(live) and live[-1] <= report.stats.cyclic_packets, (live[-5:], report.stats)
    assert report.stats.cyclic_packets > 100


def test_a_condition_that_raises_ends_the_run_and_raises():
    with axon.c4g.Server(axon.c4g.Monitor()) as server:
        with pytest.raises(ZeroDivisionError):
            server.run(until=lambda: 1 / 0)
        assert server.report.reason == "stopped"


def test_ctrl_c_ends_the_session_with_the_arm_at_rest():
    positions = raised_cosine(20.0, 0.002, [10.0, 0, 0, 0, 0, 0])
    app = axon.c4g.Stream(positions)
    with axon.c4g.Server(app) as server, \
            axon.c4g.SimulatedController(server, program=SHORT, reply_window="period") as controller:
        timer = threading.Timer(1.5, lambda: os.kill(os.getpid(), signal.SIGINT))
        timer.start()
        started = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            server.run()
        assert time.monotonic() - started < 8  # not the 20 s of the trajectory
        report = server.report
        seen = controller.wait(timeout_s=30)
    assert report.reason == "signal"
    # The app slowed the arm to rest and left mode 4; the controller came back to mode 0 and ended
    # its program without a communication error or a drive off.
    assert_answered_until_the_server_closed(report, seen)
    assert app.phase == "done"
    names = [e.name for e in seen.events]
    assert "ERR_C4GOPEN_DRIVEOFF_SERVER" not in names and "ERR_C4GOPEN_UDP" not in names
    assert 0.0 < seen.joints_deg(1)[0] < 10.0


def test_the_docs_quick_start_runs(source_dir):
    text = open(os.path.join(source_dir, "docs", "python.md"), encoding="utf-8").read()
    section = text.split("## `axon.c4g`", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env)
    assert result.returncode == 0, result.stdout + result.stderr


HANDOVER = open(os.path.join(os.path.dirname(__file__), "..", "..", "data", "c4g", "handover.yaml")).read()


def test_handover_plays_the_trajectory_in_mode_4_then_corrects_in_mode_7():
    positions = raised_cosine(0.4, 0.002, [5.0, -3.0, 2.0, 0, 4.0, 0])
    positions = np.vstack([positions, positions[::-1]])  # there and back: relative, from 0 to 0
    app = axon.c4g.Handover(positions, relative=True, amplitude_deg=0.5, frequency_hz=2.0, hold_s=0.3, ramp_s=0.1)
    report, seen = serve(app, HANDOVER)
    assert report.reason == "controller ended the exchange (504)", report.text()
    assert_every_cycle_answered(report, seen)
    assert app.phases == 2 and app.error is None, report.text()


def test_contribute_adds_a_current_sine_in_mode_9():
    app = axon.c4g.Contribute(mode=9, amplitude=0.2, frequency_hz=2.0, open_time_s=0.5, ramp_s=0.1)
    report, seen = serve(app, SHORT.replace("mode: 4", "mode: 9"))
    assert_answered_until_the_server_closed(report, seen)
    assert app.error is None and report.finished, report.text()
    assert 0.05 < max(app.peak(j) for j in range(6)) <= 0.2 + 1e-9
    with pytest.raises(axon.Error):
        axon.c4g.Contribute(mode=7)


def test_a_correction_from_a_table_and_a_rearmed_stream_are_built():
    import tempfile
    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
        f.write("# units: deg\nt,j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0,0\n0.2,0.1,0,0,0,0,0\n0.4,0,0,0,0,0,0\n")
    try:
        app = axon.c4g.Correct(file=f.name)
        report, seen = serve(app, SHORT.replace("mode: 4", "mode: 7"))
        assert_answered_until_the_server_closed(report, seen)
        assert app.error is None and app.runs == 1, report.text()  # the table played in the open phase
    finally:
        os.unlink(f.name)
    assert axon.c4g.Stream(raised_cosine(0.2, 0.002, [1.0, 0, 0, 0, 0, 0]), rearm=True) is not None
    with pytest.raises(axon.Error):
        axon.c4g.Correct(file="/nonexistent/corrections.csv")


def test_samples_give_every_cycle_as_numpy_arrays():
    positions = raised_cosine(0.6, 0.002, [3.0, 0, 0, 0, 0, 0])
    app = axon.c4g.Stream(positions, relative=True)
    taken = []
    with axon.c4g.Server(app, samples=4096, until_controller_ends=True) as server, \
            axon.c4g.SimulatedController(server, program=PROGRAM, reply_window="period") as controller:
        report = server.run(until=lambda: taken.append(server.samples()) and False)
        taken.append(server.samples())  # the rest, after the run
        seen = controller.wait(timeout_s=30)
    assert_every_cycle_answered(report, seen)
    cycles = np.concatenate([t["cycle"] for t in taken])
    assert len(cycles) == report.stats.cyclic_packets and taken[-1]["dropped"] == 0, (len(cycles), report.stats)
    assert np.all(np.diff(cycles) > 0)  # in order, none twice
    both = [t for t in taken if len(t["cycle"])]
    mode = np.concatenate([t["mode"] for t in both])
    reply = np.concatenate([t["reply"] for t in both])
    assert mode.shape[1] == 6 and reply.shape[1:] == (6, 5)
    assert (mode[:, 0] == 4).sum() > 200  # the open phase, mode 4 on axis 1
    with pytest.raises(axon.Error):
        axon.c4g.Server(axon.c4g.Monitor(), samples=10, csv="/tmp/x.csv")


SEGMENTS_PROGRAM = """steps:
  - drive_on
  - cmd: {arm: 1, value: 1}
  - go_open: {type: A, mode: 4, arms: [1]}
  - delay: 0.5
  - cmd: {arm: 1, value: 2}
  - delay: 0.5
  - cmd: {arm: 1, value: 7}
  - delay: 0.2
  - cmd: {arm: 1, value: 0}
  - wait_for_pc: {timeout: 10}
  - exit_open
"""


def test_segments_by_motion_type_are_played_as_the_program_picks_them():
    out = raised_cosine(0.3, 0.002, [4.0, 0, 0, 2.0, 0, 0])  # motion type 1: out by 4 and 2 deg
    back = -out                                               # motion type 2: back, from where 1 ended
    app = axon.c4g.Stream(segments={1: out, 2: back}, relative=True)
    report, seen = serve(app, SEGMENTS_PROGRAM)
    assert report.finished and app.error is None, report.text()
    assert app.segment == 2  # 7 has no table: it held; 0 ended the stream
    assert_every_cycle_answered(report, seen)
    np.testing.assert_allclose(seen.joints_deg(1), np.zeros(6), atol=0.05)  # out and back again


def test_bad_segments_are_refused_with_the_reason():
    table = raised_cosine(0.1, 0.002, [1.0, 0, 0, 0, 0, 0])
    for bad in ({0: table}, {256: table}, {"1": table}, {}, [table], {1: table[0]}):
        with pytest.raises(axon.Error):
            axon.c4g.Stream(segments=bad)
    with pytest.raises(axon.Error, match="not both"):
        axon.c4g.Stream(table, segments={1: table})
    with pytest.raises(axon.Error):
        axon.c4g.Stream()
    assert axon.c4g.Handover(segments={1: table, 2: table}, relative=True) is not None
