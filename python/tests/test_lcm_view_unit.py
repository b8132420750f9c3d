"""dfp-lcm-view's parts without a network: the FDL header reader and service names
(dfpsim.fdl_text), and the viewer's lines for messages built with the generated LCM types
(skipped without the lcm module). The viewer against dfp-sim: tests/lcm/test_lcm_view.sh."""

import io

import pytest

from dfpsim import fdl_text
from dfpsim.lcm_view import Viewer, baud_text, parse_args


def frame(hexstr):
    return fdl_text.parse(bytes.fromhex(hexstr))


def test_sd2_with_saps():
    f = frame("68 05 05 68 84 82 6D 3C 3E ED 16")
    assert (f.sd, f.da, f.sa, f.fc, f.dsap, f.ssap, f.du, f.fault) == \
        ("SD2", 4, 2, 0x6D, 60, 62, b"", "")
    assert fdl_text.request_service(f) == "Slave_Diag"


def test_sd1_sd3_sd4_sc():
    assert (frame("10 04 02 49 4F 16").fc, frame("10 04 02 49 4F 16").fault) == (0x49, "")
    f = frame("A2 82 84 08 3E 3C 02 05 00 FF 60 03 F1 16")
    assert (f.sd, f.da, f.sa, f.dsap, f.ssap, f.du.hex(), f.is_reply) == \
        ("SD3", 2, 4, 62, 60, "020500ff6003", True)
    assert (frame("DC 04 02").sd, frame("DC 04 02").da) == ("SD4", 4)
    assert (frame("E5").sd, frame("E5").is_reply, frame("E5").da) == ("SC", True, None)


@pytest.mark.parametrize("octets, fault", [
    ("10 04 02 49 4E 16", "bad FCS"),
    ("10 04 02 49 4F 17", "no end delimiter"),
    ("68 05 05 68 84 82 6D 3C 3E ED", "10 octets, the header says 11"),
    ("68 05 06 68 84 82 6D 3C 3E ED 16", "LE 5, LEr 6"),
    ("10 04", "cut short"),
    ("33 04 02", "unknown start delimiter 33"),
    ("", "no octets"),
])
def test_damaged_frames_keep_what_they_have(octets, fault):
    f = frame(octets)
    assert f.fault == fault
    if octets.startswith("10 04 02") or octets.startswith("68"):
        assert (f.da, f.sa) == (4, 2)


def test_address_extension_chain_skips_the_segment_octet():
    # DAE: segment address 0x45 (bit 6) with "more" (bit 7), then SAP 51; SAE: SAP 50.
    du = bytes([0xC5, 0x33, 0x32, 0x5E, 0x00, 0x2F, 0xF0])
    body = bytes([0x84, 0x82, 0x6D]) + du
    octets = bytes([0x68, len(body), len(body), 0x68]) + body + bytes([sum(body) & 0xFF, 0x16])
    f = fdl_text.parse(octets)
    assert (f.dsap, f.ssap, f.du, f.fault) == (51, 50, bytes([0x5E, 0x00, 0x2F, 0xF0]), "")
    assert fdl_text.request_service(f) == "MSAC1 read"


@pytest.mark.parametrize("octets, service", [
    ("68 07 07 68 84 82 7D 3E 3E F3 F2 E4 16", "Chk_Cfg"),
    ("68 05 05 68 04 02 7D 00 00 83 16", "Data_Exchange"),
    ("10 04 02 4E 54 16", "Request Ident"),
    ("68 06 06 68 84 82 56 3A 3E 00 00 00 16", "Global_Control"),
    ("68 05 05 68 84 82 7D 33 33 00 16", "MSAC1 poll"),
    ("68 06 06 68 84 82 7D 31 30 57 00 00 16", "MSAC2 initiate"),
    ("68 06 06 68 84 82 7D 14 30 48 00 00 16", "MSAC2 idle"),
])
def test_request_services(octets, service):
    assert fdl_text.request_service(frame(octets)) == service


def test_replies_are_named_after_the_request_on_their_channel():
    t = fdl_text.ServiceTracker()
    assert t.name("A", frame("68 05 05 68 04 02 7D 00 00 83 16"), 4, False) == "Data_Exchange"
    assert t.name("A", frame("68 05 05 68 02 04 08 00 00 0E 16"), 4, True) == \
        "Data_Exchange reply"
    assert t.name("A", frame("E5"), 4, True) == "Data_Exchange reply"
    assert t.name("A", frame("E5"), 4, False) == "reply"          # not the publisher's answer
    assert t.name("B", frame("E5"), 4, True) == "reply"           # another channel
    assert t.name("B", frame("A2 82 84 08 3E 3C 02 05 00 FF 60 03 F1 16"), 4, True) == \
        "Slave_Diag reply"                                        # from its SSAP
    assert t.name("A", frame("DC 04 02"), 4, True) == "token"


def test_baud_text():
    assert [baud_text(b) for b in (0, 9600, 187500, 1500000, 12000000, 300)] == \
        ["searching", "9.6 kbit/s", "187.5 kbit/s", "1.5 Mbit/s", "12 Mbit/s", "300 bit/s"]


def test_bad_options_exit_2():
    for argv in (["--count", "0"], ["--duration", "-1"], ["--status", "x"], ["--nope"]):
        with pytest.raises(SystemExit) as e:
            parse_args(argv)
        assert e.value.code == 2


def test_viewer_lines_through_the_generated_types():
    pytest.importorskip("lcm")
    from dfpsim import lcm_types
    types = lcm_types.load()
    out = io.StringIO()
    v = Viewer(types, out)
    tg = types["telegram_t"]()
    tg.utime, tg.station, tg.direction, tg.error_flags = 0, 4, 2, 1
    tg.data = bytes.fromhex("10 04 02 49 4E 16")
    tg.length = len(tg.data)
    v.on_message("DFP_TELEGRAM", tg.encode())
    v.on_message("DFP_TELEGRAM", tg.encode()[:20])            # cut short: undecodable
    v.on_message("OTHER", b"\x01" * 16)                       # another type
    line = out.getvalue().splitlines()[0]
    assert line.split(None, 1)[1] == ("DFP_TELEGRAM     4 RX SD1 DA   4 SA   2 FC 49  "
                                      "FDL_Status           10 04 02 49 4E 16  ! parity, bad FCS")
    assert v.counts == {"telegram": 1, "state": 0, "param": 0, "api": 0, "undecodable": 1,
                        "other": 1}
    assert v.summary_lines(1.0)[1] == "station 4: no card state; 1 telegrams, " \
                                      "Data_Exchange sent 0, errors 1"


def test_control_characters_from_the_wire_are_shown_escaped():
    # A sender on the LCM group chooses every string the viewer prints: a screen clear, an OSC
    # 52 clipboard write, a carriage return over the line and a faked line of its own.
    pytest.importorskip("lcm")
    from dfpsim import lcm_types
    types = lcm_types.load()
    out = io.StringIO()
    v = Viewer(types, out)
    ps = types["param_service_t"]()
    ps.utime, ps.address, ps.index, ps.subindex, ps.value, ps.ok = 0, 4, 8300, 0, 0, False
    ps.path = "c1-ds47\x1b]52;c;ZXZpbA==\x07"
    ps.service = "read\rwrite"
    ps.result_text = "\x1b[2Jclass 8\n00:00:00.000 FAKE       4 param ok\u202e\x9b"
    v.on_message("DFP_PARAM\x1b[31m", ps.encode())
    st = types["card_state_t"]()
    st.utime, st.address = 0, 5
    st.dp_state, st.led_run, st.led_bus_fault = "Data_Exch\x1b[H", "on\x7f", "off"
    st.p090_pd_config, st.p091_fieldbus_type = "3PD\x08\x08\x08", "PROFIBUS DP"
    v.on_message("DFP_CARD_STATE", st.encode())
    v.on_message("OTHER\x1b[2J", b"\x01" * 16)               # another type: named in the summary
    v.print_summary(1.0)
    text = out.getvalue()
    for c in ("\x1b", "\x07", "\r", "\x08", "\x7f", "\x9b", "\u202e"):
        assert c not in text
    lines = text.split("\n")
    assert lines[0].split(None, 1)[1] == (
        "DFP_PARAM\\x1b[31m   4 param c1-ds47\\x1b]52;c;ZXZpbA==\\x07 read\\x0dwrite "
        "index 8300.0 value 0 refused: \\x1b[2Jclass 8\\x0a00:00:00.000 FAKE       4 param ok"
        "\\u{202e}\\x9b")
    assert lines[1].split(None, 1)[1].startswith(
        "DFP_CARD_STATE   5 state Data_Exch\\x1b[H, searching, RUN on\\x7f, BUS FAULT off, "
        "P090 3PD\\x08\\x08\\x08, ")
    assert lines[2].startswith("summary: 2 messages") and \
        lines[2].endswith("1 of other types (OTHER\\x1b[2J)")
    assert lines[3].startswith("station 5: Data_Exch\\x1b[H, searching, RUN on\\x7f")
    assert lines[4:] == [""]


def test_api_events_are_shown_escaped():
    # The audit of a dfp-sim's control API (DFP_API): who asked for what, and the answer.
    pytest.importorskip("lcm")
    from dfpsim import lcm_types
    types = lcm_types.load()
    out = io.StringIO()
    v = Viewer(types, out)
    ev = types["api_event_t"]()
    ev.utime, ev.t_us, ev.seq, ev.level, ev.kind = 0, 3003500, 12, "warn", "audit"
    ev.text = "127.0.0.1:43600 none POST /api/v1/master/run -> 415 Content-Type\x1b[2J"
    v.on_message("DFP_API", ev.encode())
    assert out.getvalue().split(None, 1)[1] == (
        "DFP_API            api warn audit: 127.0.0.1:43600 none POST /api/v1/master/run -> "
        "415 Content-Type\\x1b[2J\n")
    assert v.counts["api"] == 1 and v.messages == 1


def test_the_status_line_shows_wire_text_escaped():
    pytest.importorskip("lcm")
    from dfpsim import lcm_types
    types = lcm_types.load()
    out = io.StringIO()
    v = Viewer(types, out, status_line=True)
    st = types["card_state_t"]()
    st.address, st.dp_state, st.led_run, st.led_bus_fault = 6, "\x1b[2J", "on", "\r"
    v.on_message("DFP_CARD_STATE", st.encode())
    # The viewer's own "\r\x1b[K" clears the line; what follows it is the station's text.
    assert out.getvalue() == "\r\x1b[K6: \\x1b[2J searching RUN on BF \\x0d DX 0 err 0"
