"""The client against the real dfp-sim: `dfp-sim demo --http` and `dfp-sim slave` / `master`.

What the commissioning checklist does not cover: the event stream and the log, the parameter
table, and that the server's errors arrive as ApiError with its text (docs/api.md, "Ground
rules").
"""

import pytest

from dfpsim import ApiError, DfpSimError, ParamError, wait_until

LOG_KINDS = {"dp_state", "baud", "watchdog", "prm", "cfg", "diag", "led", "param", "drive",
             "fault", "speed", "master", "ring", "bus", "action", "audit", "nvm", "lost"}


def test_demo_state(demo):
    st = demo.state()
    assert st["mode"] == "demo"
    assert st["read_only"] is False
    assert [c["address"] for c in st["cards"]] == [4]
    assert st["master"]["address"] == 2
    assert demo.card(4).address == 4
    wait_until(lambda: demo.card(4).dp_state == "Data_Exch", timeout=10, what="demo in Data_Exch")


def test_demo_events_and_log(demo):
    events = demo.events(timeout=5)
    try:
        seen = {}
        for ev in events:
            seen.setdefault(ev["event"], ev)
            if "state" in seen and "log" in seen:
                break
    finally:
        events.close()
    state = seen["state"]["data"]
    assert state["mode"] == "demo" and state["cards"][0]["address"] == 4
    log = seen["log"]["data"]
    assert seen["log"]["id"] == str(log["seq"])
    assert log["kind"] in LOG_KINDS
    assert log["level"] in {"error", "warn", "info", "debug"}
    held = demo.log(since=0)
    assert held, "the log holds the demo's events"
    seqs = [e["seq"] for e in held]
    assert seqs == sorted(seqs)
    assert all(e["kind"] in LOG_KINDS for e in held)
    later = demo.log(since=seqs[-1])
    assert [e["seq"] for e in later][:1] == [seqs[-1]]
    assert len(demo.log(since=0, limit=2)) == 2


def test_demo_parameter_table(demo):
    rows = demo.params("P130")
    assert any(r["p_number"] == "P130" and r["index"] == 8470 for r in rows)
    p100 = [r for r in demo.params("setpoint source") if r["p_number"] == "P100"]
    assert p100 and {"value": 3, "text": "FIELDBUS"} in p100[0]["enums"]
    assert demo.card(4).read_param("P130").p_number == "P130"


def test_demo_errors_carry_the_servers_text(demo):
    with pytest.raises(ApiError) as e:
        demo.card(9).dp_state
    assert e.value.status == 404 and e.value.message
    with pytest.raises(ApiError) as e:
        demo.card(4).inject_fault(0)                        # 1..255
    assert e.value.status == 400 and e.value.message
    with pytest.raises(ApiError) as e:
        demo.card(4).set_dip(200)                           # 0..127
    assert e.value.status == 400 and e.value.message
    with pytest.raises(ApiError) as e:
        demo.request("POST", "/api/v1/cards/4/cable", {"connected": "yes"})
    assert e.value.status == 400 and e.value.message
    with pytest.raises(ApiError) as e:
        demo.request("GET", "/api/v1/no-such-thing")
    assert e.value.status == 404
    with pytest.raises(ApiError) as e:
        demo.request("DELETE", "/api/v1/state")
    assert e.value.status == 405


def test_slave_has_no_master(bus):
    assert bus.slave.state()["master"] is None
    with pytest.raises(DfpSimError, match="has no DP master"):
        bus.slave.master().phase(4)
    with pytest.raises(ApiError) as e:
        bus.slave.master().stop()
    assert e.value.status == 409 and e.value.message


def test_master_stop_and_run(bus):
    card, plc = bus.card, bus.plc
    wait_until(lambda: card.dp_state == "Data_Exch", timeout=10, what="Data_Exch")
    wd_ms = card.watchdog_ms
    plc.stop()                      # PLC STOP: the master stops sending, the watchdog expires
    assert plc.running is False
    wait_until(lambda: card.dp_state != "Data_Exch", timeout=wd_ms / 1000.0 + 1.0,
               what="watchdog expiry after PLC STOP")
    plc.run()
    wait_until(lambda: card.dp_state == "Data_Exch", timeout=10, what="Data_Exch after RUN")
    assert plc.running is True


def test_class2_parameter_services(bus):
    card, plc = bus.card, bus.plc
    wait_until(lambda: card.dp_state == "Data_Exch", timeout=10, what="Data_Exch")
    # A class-2 read gives what a class-1 read (the cyclic channel) gives.
    for p in ("P100", "control signal source", 8470):
        assert plc.read_param(4, p, via="c2") == plc.read_param(4, p, via="channel")
    # A class-2 write, then a read by either path, sees the value.
    written = plc.write_param(4, "P160", 2250, via="c2")
    assert (written.p_number, written.index, written.value) == ("P160", 8489, 2250)
    assert plc.read_param(4, "P160", via="c2").value == 2250
    assert plc.read_param(4, "P160", via="channel").value == 2250
    assert card.read_param("P160").value == 2250
    # A refusal is the drive's, as on the other paths.
    with pytest.raises(ParamError, match="MOVILINK error"):
        plc.write_param(4, "P302", 99000000, via="c2")
    # No station at 9: the connection does not open.
    with pytest.raises(ApiError) as e:
        plc.read_param(9, "P100", via="c2")
    assert e.value.status == 502
    assert e.value.message.startswith("class-2 connection to slave 9 not opened: ")
    assert card.dp_state == "Data_Exch"
