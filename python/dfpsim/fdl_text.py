"""PROFIBUS telegrams as one line of text for dfp-lcm-view: the FDL header (start delimiter,
DA, SA, FC, SAPs), whether the frame is well formed, and the DP / DP-V1 service it belongs to,
named as dfp-sim names them (`dp_slave/src/dp_services.c`, `sim_host/replay/src/decode.c`).

The header is read leniently, as the replay check reads a capture: a frame with a wrong check
sum, length or end delimiter still shows its addresses, with the fault named. (pyprofibus's
FdlTelegram.fromRawData refuses such a frame outright, and a viewer must show those most of all.)
"""

from dataclasses import dataclass

SD1, SD2, SD3, SD4, SC, ED = 0x10, 0x68, 0xA2, 0xDC, 0xE5, 0x16
FC_REQUEST = 0x40
ADDR_EXT = 0x80   # DA/SA bit 7: an address-extension octet (a SAP) leads the data unit
AE_MORE = 0x80    # extension octet bit 7: another extension octet follows
AE_SEGMENT = 0x40  # extension octet bit 6: a segment address, not a SAP

# DP SAPs (dp_slave/include/dp_slave/dp_wire.h) and DP-V1 function codes (dpv1/.../dpv1_wire.h).
DP_SERVICES = {
    53: "Set_Ext_Prm", 55: "Set_Slave_Add", 56: "Rd_Inp", 57: "Rd_Outp", 58: "Global_Control",
    59: "Get_Cfg", 60: "Slave_Diag", 61: "Set_Prm", 62: "Chk_Cfg",
}
SAP_MSAC1, SAP_ALARM, SAP_MSAC2_RM = 51, 50, 49
DPV1_FUNCTIONS = {
    0x48: "idle", 0x51: "data transport", 0x56: "RM", 0x57: "initiate", 0x58: "abort",
    0x5C: "alarm ack", 0x5E: "read", 0x5F: "write",
}
REQUEST_FUNCTIONS = {
    0x0: "time event", 0x3: "SDA low", 0x4: "SDN low", 0x5: "SDA high", 0x6: "SDN high",
    0x7: "MSRD", 0x9: "FDL_Status", 0xA: "time event (TE)", 0xB: "counter event (CE)",
    0xC: "SRD low", 0xD: "SRD high", 0xE: "Request Ident", 0xF: "Request LSAP status",
}
DATA_FUNCTIONS = {0x4, 0x6, 0xC, 0xD}   # SDN and SRD: the functions DP services ride on
FDL_STATUS = 0x9


@dataclass
class Frame:
    """What the octets of one telegram say. Fields the frame does not carry are None."""
    sd: str = "?"            # "SD1", "SD2", "SD3", "SD4", "SC", "?"
    da: int | None = None    # 7-bit addresses
    sa: int | None = None
    fc: int | None = None
    dsap: int | None = None
    ssap: int | None = None
    du: bytes = b""          # the data unit after the SAP octets
    fault: str = ""          # "" or what is wrong with the frame, e.g. "bad FCS"

    @property
    def is_request(self):
        return self.fc is not None and self.sd != "SD4" and (self.fc & FC_REQUEST) != 0

    @property
    def is_reply(self):
        return self.sd == "SC" or (self.fc is not None and self.sd != "SD4" and
                                   (self.fc & FC_REQUEST) == 0)


def _strip_saps(frame, da, sa):
    """Takes the DSAP and SSAP extensions off the data unit (DA's first, then SA's). An
    extension is a chain of octets (bit 7: another follows); the one without the segment bit
    (6) holds the SAP."""
    du = frame.du
    for which, addr in (("dsap", da), ("ssap", sa)):
        if not addr & ADDR_EXT:
            continue
        if not du:
            frame.fault = frame.fault or "address extension without its octet"
            break
        while du:
            octet, du = du[0], du[1:]
            if not octet & AE_SEGMENT:
                setattr(frame, which, octet & 0x3F)
            if not octet & AE_MORE:
                break
    frame.du = du


def parse(octets):
    """The Frame of one telegram's octets (start delimiter to end delimiter; an SC is one)."""
    o = bytes(octets)
    if not o:
        return Frame(fault="no octets")
    kind = {SD1: "SD1", SD2: "SD2", SD3: "SD3", SD4: "SD4", SC: "SC"}.get(o[0])
    if kind is None:
        return Frame(fault="unknown start delimiter %02X" % o[0])
    if kind == "SC":
        return Frame(sd="SC", fault="" if len(o) == 1 else "%d octets after SC" % (len(o) - 1))
    if kind == "SD4":
        if len(o) < 3:
            return Frame(sd="SD4", fault="token cut short")
        return Frame(sd="SD4", da=o[1] & 0x7F, sa=o[2] & 0x7F,
                     fault="" if len(o) == 3 else "token of %d octets" % len(o))
    if kind == "SD2":
        return _parse_sd2(o)
    want = 6 if kind == "SD1" else 14
    f = Frame(sd=kind)
    if len(o) < 4:
        f.fault = "cut short"
        return f
    f.da, f.sa, f.fc = o[1] & 0x7F, o[2] & 0x7F, o[3]
    f.du = o[4:want - 2] if len(o) >= want else o[4:]
    f.fault = _trailer_fault(o, 1, want)
    _strip_saps(f, o[1], o[2])
    return f


def _parse_sd2(o):
    f = Frame(sd="SD2")
    if len(o) < 7:
        f.fault = "cut short"
        return f
    le = o[1]
    f.da, f.sa, f.fc = o[4] & 0x7F, o[5] & 0x7F, o[6]
    want = le + 6
    f.du = o[7:4 + le]
    if o[2] != le or o[3] != SD2:
        f.fault = "LE %d, LEr %d" % (le, o[2]) if o[2] != le else "second SD2 missing"
    else:
        f.fault = _trailer_fault(o, 4, want)
    _strip_saps(f, o[4], o[5])
    return f


def _trailer_fault(o, first, want):
    """Length, check sum (octets first .. want-3) and end delimiter of an SD1/SD2/SD3 frame."""
    if len(o) != want:
        return "%d octets, the header says %d" % (len(o), want)
    if sum(o[first:want - 2]) & 0xFF != o[want - 2]:
        return "bad FCS"
    if o[want - 1] != ED:
        return "no end delimiter"
    return ""


def _dpv1_service(prefix, du):
    if not du:
        return prefix + " poll"
    return "%s %s" % (prefix, DPV1_FUNCTIONS.get(du[0] & 0x7F, "function %02X" % du[0]))


def request_service(f):
    """The DP / DP-V1 service a request asks for ("Data_Exchange", "Set_Prm", "MSAC1 read"...),
    or its FDL function when it is no DP service ("FDL_Status", "Request Ident")."""
    code = f.fc & 0x0F
    if code not in DATA_FUNCTIONS:
        return REQUEST_FUNCTIONS.get(code, "FC %02X" % f.fc)
    if f.dsap is None:
        return "Data_Exchange"
    if f.dsap in DP_SERVICES:
        return DP_SERVICES[f.dsap]
    if f.dsap == SAP_MSAC1:
        return _dpv1_service("MSAC1", f.du)
    if f.dsap == SAP_ALARM:
        return "alarm SAP 50"
    if f.dsap == SAP_MSAC2_RM:
        return "MSAC2 initiate" if f.du[:1] == b"\x57" else "MSAC2 RM"
    if f.dsap <= 48:
        return _dpv1_service("MSAC2", f.du)
    return "SAP %d" % f.dsap


class ServiceTracker:
    """Names the replies: a reply carries no service of its own (a Data_Exchange answer has no
    SAPs, an SC not even addresses), so it is named after the last request to its sender on the
    same channel."""

    def __init__(self):
        self._last = {}   # (channel, responder address) -> service of the last request

    def name(self, channel, frame, publisher, tx):
        """The service of frame; publisher is the publishing station's address, tx whether it
        sent the frame (an SC is the publisher's own answer only when it sent it)."""
        if frame.sd == "SD4":
            return "token"
        if frame.fault and frame.fc is None:
            return "damaged"
        if frame.is_request:
            service = request_service(frame)
            self._last[(channel, frame.da)] = service
            return service
        responder = frame.sa if frame.sd != "SC" else (publisher if tx else None)
        service = self._last.get((channel, responder))
        if service is None and frame.ssap is not None:
            service = DP_SERVICES.get(frame.ssap)
        return (service + " reply") if service else "reply"


def hex_octets(octets):
    return " ".join("%02X" % b for b in octets)
