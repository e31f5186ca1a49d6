"""axon.can: frames, buses from spec strings (in-process virtual buses), candump logs."""

import pytest

import axon
from axon.can import Bus, Frame


def test_frames_are_made_checked_and_printed_in_cansend_notation():
    f = Frame(0x123, b"\xde\xad\xbe\xef")
    assert (f.id, f.dlc, f.data, f.is_extended, f.is_remote) == (0x123, 4, b"\xde\xad\xbe\xef", False, False)
    assert str(f) == "123#DEADBEEF"
    assert Frame.parse("123#DEADBEEF") == f
    assert Frame(0x1ABCDEF0, b"\x01").is_extended
    assert Frame(0x12, remote=True, dlc=4).is_remote
    assert repr(f) == "axon.can.Frame('123#DEADBEEF')"
    with pytest.raises(axon.can.InvalidFrame):
        Frame(0x123, bytes(9))
    with pytest.raises(axon.can.ParseError):
        Frame.parse("12G#00")


def test_two_buses_on_one_virtual_medium_see_each_others_frames():
    with Bus("virtual:pytest0") as a, Bus("virtual:pytest0") as b:
        a.send(Frame(0x100, b"\x01"))
        got = b.recv(timeout_s=2.0)
        assert got == Frame(0x100, b"\x01")
        assert a.recv(timeout_s=0.05) is None  # a sender does not hear itself
        assert a.stats.frames_out == 1 and b.stats.frames_in == 1
        assert b.state == "active"


def test_filters_pass_only_the_matching_ids():
    with Bus("virtual:pytest1") as a, Bus("virtual:pytest1") as b:
        b.set_filters(["200:7FF"])
        a.send(Frame(0x100))
        a.send(Frame(0x200, b"\x02"))
        assert b.recv(timeout_s=2.0) == Frame(0x200, b"\x02")
        assert b.recv(timeout_s=0.05) is None
        assert b.stats.rx_filtered == 1


def test_a_closed_bus_raises_closed_and_ends_iteration():
    bus = Bus("virtual:pytest2")
    bus.close()
    assert bus.state == "closed"
    with pytest.raises(axon.can.Closed):
        bus.send(Frame(0x1))
    assert list(bus) == []  # iterating a closed bus ends at once
    with pytest.raises(axon.can.Closed):
        bus.recv(timeout_s=0.01)


def test_bad_specs_and_refused_connections_raise_their_types():
    with pytest.raises(axon.can.ParseError):
        Bus("nonsense://x")
    with pytest.raises(axon.ConnectionError):
        Bus("socketcand://127.0.0.1:1/can0", connect_timeout_s=1.0)


def test_a_candump_log_is_written_and_iterated(tmp_path):
    path = tmp_path / "dump.log"
    frames = [Frame(0x100 + i, bytes([i])) for i in range(5)]
    with axon.can.LogWriter(str(path)) as w:
        for f in frames:
            w.write(f, "vcan0")
    entries = list(axon.can.read_log(str(path)))
    assert [e.frame for e in entries] == frames
    assert {e.iface for e in entries} == {"vcan0"}


def test_a_bad_log_line_raises_unless_skipped(tmp_path):
    path = tmp_path / "bad.log"
    path.write_text("(1.000000) can0 123#01\nnot a line\n(2.000000) can0 124#02\n")
    with pytest.raises(axon.can.ParseError):
        list(axon.can.LogReader(str(path)))
    reader = axon.can.LogReader(str(path), skip_bad=True)
    assert [str(e.frame) for e in reader] == ["123#01", "124#02"]
    assert reader.lines_skipped == 1
