"""axon.fps.Client against the focal plane simulated in this process."""

import time

import numpy as np
import pytest

import axon


def test_discovery_finds_every_robot_ready(benchtop):
    with axon.fps.Client() as fps:
        fps.open(benchtop.layout)
        robots = fps.discover()
        assert len(robots) == 6 and all(r.ready for r in robots)
        assert sorted(fps.robots) == sorted(int(i) for i in benchtop.layout.ids)


def test_the_status_table_is_a_numpy_record_array(client):
    table = client.status_table()
    assert len(table) == 6
    assert set(table.state) == {"ready"}
    assert np.allclose(table.beta, 180.0, atol=0.1)


def test_goto_moves_the_robots_to_their_targets(client, benchtop):
    ids = client.robots[:2]
    outcome = client.goto({ids[0]: (30.0, 150.0), ids[1]: (45.0, 160.0)})
    assert outcome.completed, outcome.summary
    assert benchtop.arms(ids[0]) == pytest.approx((30.0, 150.0), abs=0.1)
    assert outcome.robots[0].reached == pytest.approx((30.0, 150.0), abs=0.1)


def test_trajectories_from_numpy_run_to_their_last_points(client, benchtop):
    rid = client.robots[0]
    alpha = np.array([[10.0, 1.0], [20.0, 2.0]])  # degrees, seconds after the start
    beta = np.array([[170.0, 1.5]])
    outcome = client.run_trajectories({rid: (alpha, beta)})
    assert outcome.completed, outcome.summary
    assert benchtop.arms(rid) == pytest.approx((20.0, 170.0), abs=0.1)


def test_a_plan_from_python_runs_on_the_robots(client, benchtop):
    layout = benchtop.layout
    target = axon.fps.random_poses(layout, seed=2)
    where = {int(r.id): (r.alpha, r.beta) for r in client.status_table()}
    start = np.array([where[int(i)] for i in layout.ids])  # layout order
    p = axon.fps.plan(layout, start, target, seed=2)
    assert p.verified
    outcome = client.run_trajectories(axon.fps.plan_paths(p))
    assert outcome.completed, outcome.summary
    for rid, end in zip(layout.ids, p.end):
        assert benchtop.arms(int(rid)) == pytest.approx(tuple(end), abs=0.1)
    assert benchtop.collisions == 0


def test_plan_and_move_reaches_every_planned_end(client, benchtop):
    targets = {rid: (60.0 + 10 * k, 160.0) for k, rid in enumerate(client.robots)}
    done = client.plan_and_move(targets)
    assert done.plan.verified and done.move.completed
    for rid, end in done.plan.ends.items():
        assert benchtop.arms(rid) == pytest.approx(end, abs=0.1)


def test_a_stopped_array_refuses_moves_until_unlocked(client):
    rid = client.robots[0]
    client.emergency_stop("test")
    assert client.locked and "test" in client.lock_reason
    with pytest.raises(axon.fps.MotionLocked) as e:
        client.goto({rid: (20.0, 170.0)})
    assert not isinstance(e.value, axon.fps.CollisionLocked)
    client.unlock()
    assert not client.locked
    assert client.goto({rid: (20.0, 170.0)}).completed


def test_a_collision_locks_the_array_and_moves_raise_collision_locked(client, benchtop):
    rid = client.robots[0]
    client.goto({rid: (40.0, 170.0)})
    benchtop.inject_collision(rid)
    for _ in range(200):  # the robot's collision report locks the array when it arrives
        if client.locked:
            break
        time.sleep(0.01)
    assert client.locked and "collision" in client.lock_reason
    with pytest.raises(axon.fps.CollisionLocked):
        client.goto({rid: (50.0, 170.0)})
    client.unlock()
    assert client.goto({rid: (50.0, 170.0)}).completed


def test_after_a_collision_and_unlock_the_robot_backs_off_two_degrees(client, benchtop):
    rid = client.robots[0]
    benchtop.inject_collision(rid)
    for _ in range(200):
        if client.locked:
            break
        time.sleep(0.01)
    with pytest.raises(axon.fps.CollisionLocked):
        client.back_off([rid])
    client.unlock()
    before = benchtop.arms(rid)
    out = client.back_off([rid])
    assert out and out.ok, out.summary
    assert [m.id for m in out.moves] == [rid] and out.moves[0].moved
    assert out.moves[0].arm in ("alpha", "beta") and abs(out.moves[0].step_deg) >= 2.0
    after = benchtop.arms(rid)
    assert max(abs(after[0] - before[0]), abs(after[1] - before[1])) == pytest.approx(abs(out.moves[0].step_deg), abs=0.1)
    assert client.back_off().contacts_before == []  # nothing in contact: nothing to do


def test_calls_on_an_unopened_client_and_unknown_robots_raise_their_types(benchtop):
    fps = axon.fps.Client()
    with pytest.raises(axon.fps.InvalidArgument):
        fps.discover()
    fps.open(benchtop.layout)
    fps.discover()
    with pytest.raises(axon.fps.UnknownPositioner):
        fps.goto({2000: (10.0, 170.0)})
    fps.close()


def test_moving_500_simulated_robots(tmp_path):
    with axon.fps.SimulatedPlane("default", time_scale=20.0) as plane, axon.fps.Client() as fps:
        fps.open(plane.layout)
        assert len(fps.discover()) == 500
        targets = {int(rid): (60.0 + 15.0 * (k % 7), 160.0) for k, rid in enumerate(plane.layout.ids)}
        done = fps.plan_and_move(targets)
        assert done.plan.verified and done.move.completed, done.move.summary
        worst = max(abs(a - b) for rid, end in done.plan.ends.items() for a, b in zip(plane.arms(rid), end))
        assert worst <= 0.1
        assert plane.collisions == 0


def test_upgrade_firmware_reports_progress_and_every_robot_runs_the_new_image():
    with axon.fps.SimulatedPlane("benchtop", time_scale=20.0) as plane:
        with axon.fps.Client(poll_interval_s=0.02, discover_window_s=0.3, plc_address=plane.plc_address) as fps:
            fps.open(plane.layout)
            fps.discover()
            lines = []
            image = axon.fps.simulated_firmware_image("04.02.00")
            out = fps.upgrade_firmware(image, expected_version="04.02.00", power_off_s=0.05, progress=lines.append)
            assert out and out.ok, out.summary
            assert {r.after for r in out.robots} == {"04.02.00"} and len(out.robots) == 6
            assert lines and lines[-1].finished and lines[-1].done == 6, lines
            assert {r.firmware for r in fps.status()} == {"04.02.00"}
            with pytest.raises(axon.Error):
                fps.upgrade_firmware(image, expected_version="four")


def test_check_layout_and_the_cold_policy_through_the_plc():
    with axon.fps.SimulatedPlane("benchtop", time_scale=20.0) as plane:
        with axon.fps.Client(discover_window_s=0.3, plc_address=plane.plc_address) as fps:
            fps.open(plane.layout)
            fps.discover()
            check = fps.check_layout()
            assert check and check.ok, str(check)
            assert sorted(check.matched) == sorted(r.id for r in plane.layout.robots)
            assert check.missing == [] and check.wrong_bus == {} and check.unexpected == {}
            cold = fps.apply_cold_policy()
            assert cold, str(cold)
            assert sorted(cold.applied) == sorted(check.matched) and cold.failed == {}
            assert cold.motor_rpm > 0 and cold.coldest_c is not None, str(cold)
    with axon.fps.SimulatedPlane("benchtop") as plane:
        with axon.fps.Client() as fps:  # no PLC given: a clear error, nothing sent
            fps.open(plane.layout)
            with pytest.raises(axon.Error, match="needs the PLC"):
                fps.apply_cold_policy()


def test_a_start_by_the_sync_line_through_the_plc():
    with axon.fps.SimulatedPlane("benchtop", time_scale=20.0) as plane:
        with axon.fps.Client(discover_window_s=0.3, plc_address=plane.plc_address) as fps:
            fps.open(plane.layout)
            ids = [r.id for r in fps.discover()]
            paths = {i: (np.array([[25.0, 1.0]]), np.array([[165.0, 1.0]])) for i in ids}
            moved = fps.run_trajectories(paths, by_sync_line=True)
            assert moved.completed, moved.summary
            assert plane.sync_edges == 1  # one pulse started them all
            np.testing.assert_allclose([plane.arms(i) for i in ids], [(25.0, 165.0)] * len(ids), atol=0.1)
            done = fps.plan_and_move({i: (45.0, 150.0) for i in ids}, start_by_sync_line=True)
            assert done.move.completed and plane.sync_edges == 2
    with axon.fps.SimulatedPlane("benchtop") as plane:
        with axon.fps.Client() as fps:  # no PLC: refused before anything moves
            fps.open(plane.layout)
            fps.discover()
            with pytest.raises(axon.Error, match="needs the PLC"):
                fps.run_trajectories({1: (np.array([[25.0, 1.0]]), np.zeros((0, 2)))}, by_sync_line=True)
            assert plane.arms(1) == pytest.approx((0.0, 180.0), abs=0.01)
