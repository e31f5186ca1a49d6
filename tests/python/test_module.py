"""The package: its version and the error hierarchy every submodule raises into."""

import builtins

import pytest

import axon


def test_version_is_the_projects():
    assert axon.__version__.count(".") == 2
    assert all(part.isdigit() for part in axon.__version__.split("."))


def test_errors_form_one_hierarchy_with_the_builtin_meanings():
    assert issubclass(axon.TimeoutError, axon.Error)
    assert issubclass(axon.TimeoutError, builtins.TimeoutError)
    assert issubclass(axon.InvalidArgument, ValueError)
    assert issubclass(axon.ConnectionError, builtins.ConnectionError)
    assert issubclass(axon.fps.CollisionLocked, axon.fps.MotionLocked)
    assert issubclass(axon.fps.MotionLocked, axon.fps.Error)
    assert issubclass(axon.fps.Error, axon.Error)
    assert issubclass(axon.fps.Timeout, axon.TimeoutError)
    assert issubclass(axon.fps.BadTarget, axon.fps.PlanError)
    assert issubclass(axon.can.Closed, axon.ClosedError)
    assert issubclass(axon.can.InvalidFrame, axon.InvalidArgument)
    assert axon.fps.MotionLocked.__module__ == "axon.fps"


def test_an_error_carries_its_category_code_and_detail():
    with pytest.raises(axon.can.InvalidFrame) as e:
        axon.can.Frame(0x800, extended=False)
    assert e.value.category == "axon.can"
    assert e.value.code == 1  # CanErrc::invalid_id
    assert e.value.reason
    assert str(e.value)
