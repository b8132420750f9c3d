#!/usr/bin/env python3
"""Instructions from the last request character to the first reply character, per telegram type,
counted on the target under QEMU (netduinoplus2, Cortex-M4 TCG).

Method: QEMU runs the image with `-singlestep -d exec,nochain -D TRACE`: one trace line per
executed instruction, with its PC. For every reply, count the instructions from the entry of the
dfp21b_rx_char call that took the request's last character (in the PendSV drain) to the entry
of rs485_uart_transmit (FCS/ED, FDL, DP service, DP-V1 SAP, encoding, FCB cache), leaving out
SysTick (its own interrupt, at most one per reply), and add the driver's share for a lone
character measured in the same trace: the largest USART1 interrupt that stored exactly one
character (clock read included) and the largest PendSV drain that handed on exactly one. Not
counted: the exception entries themselves (12 cycles, 6 for the tail-chain into PendSV) and a
wait for the main loop when it held PendSV off (BASEPRI); that wait is reported on its own: the
thread-mode instructions of each main-loop pass from its BASEPRI raise to the lower around
dfp21b_poll (QEMU sets bit 0 of the trace's cs_base field in handler mode), interrupts left
out. QEMU often hands a telegram over in one burst; the whole drain after such a telegram's last
interrupt is reported separately. Then add each reply's transmit tail, without the min TSDR
spin (a fresh not_before has already passed at 12 Mbit/s): transmit entry to its
first clock read, one clock read, and from the spin's last clock read to the first DR write in
tx_fill. Each reply is labelled by the core functions that ran between the last character and
transmit (classify_funcs); the captures only give the count and the largest reply.

usage: reply_path_count.py ELF TRACE CAPTURE.pcap [CAPTURE.pcap ...]
"""
import re
import struct
import subprocess
import sys
from collections import defaultdict

BAUDS = [12000000, 6000000, 3000000, 1500000, 500000, 187500, 93750, 45450, 19200, 9600]
MHZ = 168


def symbols(elf):
    out = subprocess.run(["arm-none-eabi-nm", "-S", elf], capture_output=True, text=True).stdout
    syms = {}
    for l in out.splitlines():
        p = l.split()
        if len(p) == 4 and p[2] in "tT":
            syms[p[3]] = (int(p[0], 16) & ~1, int(p[1], 16))
    return syms


def first_dr_store(elf, start, size):
    """Address of the first store to DR (str/strb with offset #4) in tx_fill."""
    out = subprocess.run(["arm-none-eabi-objdump", "-d", "--start-address=%d" % start,
                          "--stop-address=%d" % (start + size), elf],
                         capture_output=True, text=True).stdout
    for l in out.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+\S+(?: \S+)?\s+(str\w*)\s+.*\[r\d+, #4\]", l)
        if m:
            return int(m.group(1), 16)
    return None


def basepri_writes(elf, start, size):
    """(raise, lower) addresses of the main loop's BASEPRI writes around its dfp21b_poll call:
    the nearest `msr BASEPRI, rN` before the `bl dfp21b_poll` where the last write to rN loads
    a non-zero immediate, and the nearest after it where that write loads zero."""
    out = subprocess.run(["arm-none-eabi-objdump", "-d", "--start-address=%d" % start,
                          "--stop-address=%d" % (start + size), elf],
                         capture_output=True, text=True).stdout
    insns = []
    for l in out.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+[0-9a-f]{4}(?: [0-9a-f]{4})?\s+(.*)$", l)
        if m:
            insns.append((int(m.group(1), 16), m.group(2).split("@")[0].strip()))
    call = next((i for i, (_, t) in enumerate(insns) if re.match(r"bl\s+\S+ <dfp21b_poll>", t)),
                None)
    if call is None:
        return None

    def basepri_at(i, want_zero):
        m = re.match(r"msr\s+BASEPRI, (r\d+)$", insns[i][1])
        if not m:
            return False
        # the last instruction before it that writes the register must load an immediate
        for j in range(i - 1, max(i - 9, -1), -1):
            if re.match(r"\S+\s+%s(?:,|$)" % m.group(1), insns[j][1]):
                k = re.match(r"movs?(?:\.w)?\s+%s, #(\d+)$" % m.group(1), insns[j][1])
                return k is not None and (int(k.group(1)) == 0) == want_zero
        return False

    raise_at = next((insns[i][0] for i in range(call - 1, -1, -1) if basepri_at(i, False)), None)
    lower_at = next((insns[i][0] for i in range(call + 1, len(insns)) if basepri_at(i, True)),
                    None)
    if raise_at is None or lower_at is None:
        return None
    return raise_at, lower_at


def classify_funcs(funcs):
    """The request a reply answers, told by the core functions that ran for it (robust against
    replies QEMU's pace made the firmware drop, which pairing with the captures is not)."""
    def ran(prefix):
        return any(f == prefix or f.startswith(prefix + ".") for f in funcs)
    if ran("fdl_station_reply_rs"):
        return "refused (RS)"
    if "hook_prm_check" in funcs:
        return "Set_Prm (SC)"
    if "hook_cfg_check" in funcs:
        return "Chk_Cfg (SC)"
    if ran("dp_slave_build_diag"):
        return "Slave_Diag"
    if "hook_outputs" in funcs:
        return "Data_Exchange"
    if "dpv1_sap_request" in funcs:
        if ran("fdl_station_reply_sap"):
            # the resource manager frees the slot it opens (conn_close) before an Initiate
            return "DP-V1 MSAC2 Initiate (RM)" if "conn_close" in funcs else "DP-V1 response with data"
        if "conn_close" in funcs:
            return "DP-V1 Abort (SC)"
        return "DP-V1 request taken (SC)"
    if "dp_slave_request" not in funcs and "fcb_touch" in funcs:
        return "repeat from the FCB cache"
    if "dp_slave_request" not in funcs and ran("fdl_station_reply_plain"):
        return "FDL status (SD1)"
    return "other (Get_Cfg, Rd_Inp, Rd_Outp, ...)"


def classify(req):
    sd = req[0]
    if sd == 0x10:
        return "FDL status (SD1)" if (req[3] & 0x0F) == 0x09 else "SD1 other"
    if sd == 0xA2:
        return "Data_Exchange SD3 8 B"
    if sd != 0x68:
        return "other"
    da, sa = req[4], req[5]
    data = req[7:-2]
    if not (da & 0x80):
        return "Data_Exchange %d B" % len(data)
    dsap = data[0]
    names = {60: "Slave_Diag", 61: "Set_Prm", 62: "Chk_Cfg", 59: "Get_Cfg", 58: "Global_Control",
             56: "Rd_Inp", 57: "Rd_Outp", 51: "DP-V1 MSAC1", 49: "DP-V1 MSAC2 Initiate (RM)"}
    if dsap in names:
        return names[dsap]
    return "DP-V1 MSAC2 connection"


def pairs(paths):
    out = []
    for p in paths:
        d = open(p, "rb").read()
        o = 24
        recs = []
        while o + 16 <= len(d):
            _, _, cl, _ = struct.unpack("<IIII", d[o:o + 16])
            recs.append(d[o + 16:o + 16 + cl])
            o += 16 + cl
        for i, r in enumerate(recs):
            is_req = (r[0] in (0x10, 0x68, 0xA2)) and (
                (r[0] == 0x68 and (r[4] & 0x7F) == 4) or (r[0] != 0x68 and (r[1] & 0x7F) == 4))
            if is_req and i + 1 < len(recs):
                nxt = recs[i + 1]
                nxt_is_req = nxt[0] != 0xE5 and (
                    (nxt[0] == 0x68 and (nxt[4] & 0x7F) == 4) or
                    (nxt[0] in (0x10, 0xA2) and (nxt[1] & 0x7F) == 4))
                if not nxt_is_req:
                    out.append((classify(r), r, nxt))
    return out


def main():
    elf, trace, caps = sys.argv[1], sys.argv[2], sys.argv[3:]
    s = symbols(elf)
    for need in ("fdl_station_reply_plain", "fdl_station_reply_sap", "dp_slave_build_diag", "hook_prm_check",
                 "hook_cfg_check", "hook_outputs", "dpv1_sap_request", "conn_close", "fcb_touch"):
        if not any(n == need or n.startswith(need + ".") for n in s):
            sys.exit("reply_path_count: no function %s in the image; the labels need updating" % need)
    isr = s["USART1_IRQHandler"][0]
    pendsv = s["PendSV_Handler"][0] if "PendSV_Handler" in s else None
    rx_char = s["dfp21b_rx_char"][0]
    # The driver's share for a lone character, as on a real line (QEMU often hands over several
    # at once): the largest USART1 interrupt that stored exactly one (its clock read included),
    # and the largest PendSV drain that handed on exactly one.
    drain_funcs = [(s[n][0], s[n][0] + s[n][1]) for n in
                   ("PendSV_Handler", "rs485_uart_rx_drain", "uart_rx") if n in s]
    isr_one = []
    drain_one = []
    cur_isr = None    # [instructions, characters] of the interrupt running
    cur_drain = None  # same for the last PendSV
    rx_calls = 0
    last_char_at = 0
    gi = 0  # instructions so far, SysTick left out
    isr_funcs = [(s[n][0], s[n][0] + s[n][1]) for n in
                 ("USART1_IRQHandler", "rs485_uart_isr", "rx_store", "uart_rx_pending", "now_us",
                  "timebase_now_us") if n in s]
    tx = s["rs485_uart_transmit"][0]
    fill_a, fill_n = s["tx_fill"]
    now_a = s["now_us"][0] if "now_us" in s else s["timebase_now_us"][0]
    dr_store = first_dr_store(elf, fill_a, fill_n)
    excl = []
    for n in ("SysTick_Handler", "timebase_tick", "board_leds_tick"):
        if n in s:
            excl.append((s[n][0], s[n][0] + s[n][1]))
    # The first field is QEMU's cs_base; for M-profile its bit 0 is set in handler mode.
    line_re = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[([0-9a-f]+)/([0-9a-f]+)/[0-9a-f]+/[0-9a-f]+\] ?(\S*)")
    funcs = set()  # functions run since the last dfp21b_rx_char call
    masked = basepri_writes(elf, *s["main"])
    if masked is None:
        sys.exit("reply_path_count: no BASEPRI raise/lower around dfp21b_poll in main")
    masked_at = None  # thread-mode instructions of the main-loop pass holding PendSV off
    masked_irq = 0    # interrupt instructions that ran inside it (QEMU's pace, not the line's)
    passes = []
    results = []
    count = None
    tail = None
    tails = []
    state = None
    in_isr = False
    chained = False
    chars = 0
    refused = 0
    pending = None
    with open(trace, errors="replace") as f:
        for l in f:
            m = line_re.match(l)
            if not m:
                continue
            pc = int(m.group(2), 16)
            handler = int(m.group(1), 16) & 1
            if pc == isr and not handler:
                sys.exit("reply_path_count: USART1_IRQHandler runs with cs_base bit 0 clear; this "
                         "QEMU does not mark handler mode there (QEMU >= 6.1 does)")
            if not handler and pc == masked[0]:
                masked_at, masked_irq = 0, 0
            elif masked_at is not None:
                if not handler and pc == masked[1]:
                    passes.append((masked_at, masked_irq))
                    masked_at = None
                elif handler:
                    masked_irq += 1
                else:
                    masked_at += 1
            if any(a <= pc < b for a, b in excl):
                continue
            if pc == isr:
                count = 0
                chars = 0
                in_isr = True
                chained = pendsv is None
                cur_isr = [0, 0]
            elif in_isr and not any(a <= pc < b for a, b in isr_funcs):
                in_isr = False
                chained = pc == pendsv
                if cur_isr[1] == 1:
                    isr_one.append(cur_isr[0])
            if in_isr:
                cur_isr[0] += 1
                if pc == now_a:
                    cur_isr[1] += 1
            if pendsv is not None and pc == pendsv:
                if cur_drain is not None and cur_drain[1] == 1:
                    drain_one.append(cur_drain[0])
                cur_drain = [0, 0]
            if cur_drain is not None and any(a <= pc < b for a, b in drain_funcs):
                cur_drain[0] += 1
            gi += 1
            if pc == rx_char:
                funcs = set()
            funcs.add(m.group(3))
            if pc == rx_char:
                rx_calls += 1
                last_char_at = gi
                if cur_drain is not None:
                    cur_drain[1] += 1
            if count is not None:
                count += 1
                if pc == rx_char:
                    chars += 1
            if tail is not None and pc in (isr, rx_char, tx):
                refused += 1  # transmit returned without sending (late: characters waiting)
                tail = None
            if pc == tx:
                # "whole" (the drain of a burst) only when a USART interrupt came since the last
                # transmit; the reply path itself counts from the last character in any case
                burst = count is not None and chained
                pending = (count - 1 if burst else None, chars if count is not None else 0,
                           gi - last_char_at, classify_funcs(funcs))
                count = None
                tail = {"n": 0, "nows": []}
                continue
            if tail is not None:
                tail["n"] += 1
                if pc == now_a:
                    tail["nows"].append(tail["n"])
                if dr_store is not None and pc == dr_store:
                    nows = tail["nows"]
                    if len(nows) >= 2:
                        per_call = nows[1] - nows[0]
                        t = nows[0] + per_call + (tail["n"] - nows[-1])
                    else:
                        t = tail["n"]
                    tails.append(t)
                    results.append(pending + (t,))
                    tail = None
    tail_max = max(tails) if tails else 0
    ps = pairs(caps)
    largest = max((len(rsp), kind) for kind, _, rsp in ps) if ps else (0, "")
    per_char = [max(isr_one) if isr_one else 0, max(drain_one) if drain_one else 0]
    driver_cost = per_char[0] + per_char[1]
    core = defaultdict(list)
    backlog = []
    for whole, chars, last, kind, own_tail in results:
        core[kind].append(last + own_tail)
        if whole is not None and chars > 1:
            backlog.append((whole + own_tail, chars, kind))
    print("Reply path on the target (QEMU netduinoplus2, TCG single-step), per telegram type "
          "(told by the core functions that ran for it): the request's last character through "
          "the driver (USART1 interrupt into the ring, PendSV "
          "drain) and the core to the first reply character")
    print("driver for a lone character: USART1 interrupt storing it %d (of %d such), PendSV "
          "drain handing it on %d (of %d such) instructions; transmit tail (clock read, DE, RE "
          "off, first DR write; it grows with the frame, which transmit copies first): %d to %d, "
          "each reply counted with its own; %d characters in all; %d replies in the trace, %d in "
          "the captures, the largest %d octets (%s)"
          % (per_char[0], len(isr_one), per_char[1], len(drain_one), min(tails) if tails else 0,
             tail_max, rx_calls, len(results), len(ps), largest[0], largest[1]))
    hdr = "| telegram | n | instr. worst | instr. min | µs at %d MHz (1 instr./cycle) |" % MHZ
    hdr += " bit times at " + " / ".join("%g" % (b / 1e6) if b >= 1e6 else "%gk" % (b / 1e3)
                                          for b in BAUDS[:5]) + " |"
    print(hdr)
    print("|---|---:|---:|---:|---:|---:|")
    for kind in sorted(core, key=lambda k: -max(core[k])):
        w = max(core[kind]) + driver_cost
        us = w / MHZ
        bits = " / ".join("%.1f" % (us * b / 1e6) for b in BAUDS[:5])
        print("| %s | %d | %d | %d | %.2f | %s |" % (kind, len(core[kind]), w,
                                                   min(core[kind]) + driver_cost, us, bits))
    if refused:
        print("replies not sent because characters after the request were waiting: %d" % refused)
    for n, c, kind in sorted(backlog, reverse=True)[:2]:
        print("QEMU hands a telegram over in one burst: %s with %d characters drained at once took "
              "%d instructions from its last interrupt (%.2f µs)" % (kind, c, n, n / MHZ))
    if not passes:
        sys.exit("reply_path_count: no complete main-loop pass in the trace")
    worst, irq = max(passes)
    print("main-loop pass holding PendSV off (BASEPRI: dfp21b_poll, the SBus link, here the "
          "SBus stand-in inverter; on a card with a CAN bus the CAN drain instead): "
          "worst %d instructions of its own (%.2f µs), median %d, %d passes; interrupts that "
          "ran inside the worst: %d instructions at QEMU's single-step pace"
          % (worst, worst / MHZ, sorted(p[0] for p in passes)[len(passes) // 2], len(passes),
             irq))
    return 0


if __name__ == "__main__":
    sys.exit(main())
