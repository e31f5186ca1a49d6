"""Ctrl-C while a blocking call waits: KeyboardInterrupt, and the devices stopped."""

import os
import signal
import threading
import time

import pytest

import axon


def ctrl_c_after(seconds):
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def test_ctrl_c_during_a_long_goto_stops_every_robot():
    # Real time (time_scale 1): 300 degrees of alpha at 12 deg/s take 25 s.
    with axon.fps.SimulatedPlane("benchtop", time_scale=1.0) as plane, axon.fps.Client() as fps:
        fps.open(plane.layout)
        fps.discover()
        rid = fps.robots[0]
        ctrl_c_after(1.0)
        started = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            fps.goto({rid: (300.0, 180.0)})
        assert time.monotonic() - started < 10  # not the 25 s of the move
        assert fps.locked and "KeyboardInterrupt" in fps.lock_reason
        stopped_at = plane.arms(rid)
        time.sleep(0.5)
        assert plane.arms(rid) == stopped_at  # it stays where the stop caught it
        assert 0.0 < stopped_at[0] < 300.0
        assert all(r.state != "moving" for r in fps.status())
        fps.unlock()
        assert fps.goto({rid: (10.0, 180.0)}).completed  # usable again after unlock()


def test_ctrl_c_ends_a_receive_that_waits_without_a_timeout():
    with axon.can.Bus("virtual:interrupt") as bus:
        ctrl_c_after(0.3)
        started = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            bus.recv()
        assert time.monotonic() - started < 5
