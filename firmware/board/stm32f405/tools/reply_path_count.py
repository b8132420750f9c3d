#!/usr/bin/env python3
"""Instruction counts of the card's real-time paths on the target, under QEMU (netduinoplus2,
Cortex-M4 TCG), against the budgets of docs/performance.md; exits 1 when one is exceeded.

Method: QEMU runs the image with `-singlestep -d exec,nochain -D TRACE`: one trace line per
executed instruction, with its PC and (bit 0 of cs_base) whether the core is in handler mode.
SysTick's instructions are left out everywhere (its own interrupt, at most one per reply).

- Per received character: each USART1 interrupt that took a character, from its entry to its
  return (the functions it can call, RX_ISR_FUNCS). An interrupt that ran only the collector's
  fast path is an interior character (budget PER_CHAR_BUDGET); one that ran the collector's slow
  path or step (a start delimiter, LE, SD2) is reported beside it; one that handed a telegram
  over belongs to the reply path.
- Reply path: from the entry of the USART1 interrupt that handed the request over to the first
  write of the reply into DR (tx_fill), handler-mode instructions only (thread-mode ones are the
  main loop holding PendSV off, reported on their own), with the min TSDR spin
  (rs485_wait_until) counted as one pass, as at 12 Mbit/s where a fresh deadline has passed.
  Not counted: exception entries (12 cycles, 6 for the tail-chain into PendSV). Each reply is
  labelled by the core functions that ran for it (classify_funcs).
- Work after the reply: a service that sends its reply early (Chk_Cfg, Data_Exchange) goes on
  with the rest of its work, and the receive path frames the diagnosis again. Counted from the
  reply's first DR write until the receive path is back in the queue drain, handler-mode
  instructions outside the USART interrupt and outside tx_fill/tx_finish (POST_REPLY_BUDGET):
  QEMU's USART takes the whole frame at once, so tx_fill's loop runs it out right after the
  first write, where a real USART raises one TXE interrupt per character. On a line it cannot delay the
  next reply: the next request cannot end sooner than our reply's first character, TSYN and the
  shortest request (11 + 33 + 66 = 110 bit times at 12 Mbit/s, 1 540 cycles), and the budget
  leaves room for that request's six character interrupts. QEMU's USART, though, delivers the
  next request at once, so a reply whose request came in during that work would count it; those
  instructions are counted here, not there.
- Main-loop section: thread-mode instructions from an entry of core_enter (BASEPRI raised,
  PendSV held off) to the next entry of core_leave, interrupts left out. The main loop runs the
  core in such sections and lowers BASEPRI between them (dfp21b's preempt hook), so the longest
  section is what can hold a reply off.
- RAM (.data + .bss + .noinit + the .stack reservation) and flash (.isr_vector + .text +
  .rodata + .data's load image) of the card image, when --card ELF is given.

usage: reply_path_count.py [--card CARD.elf] ELF TRACE CAPTURE.pcap [CAPTURE.pcap ...]
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


def classify_funcs(funcs):
    """The request a reply answers, told by the core functions that ran for it (robust against
    replies QEMU's pace made the firmware drop, which pairing with the captures is not)."""
    def ran(prefix):
        return any(f == prefix or f.startswith(prefix + ".") for f in funcs)
    if ran("fdl_station_reply_rs"):
        return "refused (RS)"
    if "hook_prm_check" in funcs:
        return "Set_Prm (SC)"
    # Chk_Cfg and Data_Exchange send their reply before the device's hooks run
    # (fdl_station_send_now): their service function is what tells them apart
    if "hook_cfg_check" in funcs or ran("svc_chk_cfg"):
        return "Chk_Cfg (SC)"
    if ran("svc_slave_diag"):
        return "Slave_Diag"
    if "hook_outputs" in funcs or ran("svc_data_exchange"):
        return "Data_Exchange"
    if "dpv1_sap_request" in funcs:
        if ran("fdl_station_reply_framed"):
            # the resource manager frees the slot it opens (conn_close) before an Initiate
            return "DP-V1 MSAC2 Initiate (RM)" if "conn_close" in funcs else "DP-V1 response with data"
        if "conn_close" in funcs:
            return "DP-V1 Abort (SC)"
        return "DP-V1 request taken (SC)"
    # a retry is answered by pointing the transmitter at the cached reply: nothing is framed
    if "dp_slave_request" not in funcs and not ran("fdl_frame_in_place"):
        return "repeat from the FCB cache"
    if "dp_slave_request" not in funcs:
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


PER_CHAR_BUDGET = 40
FAST_REPLY_BUDGET = 600  # FDL status, Slave_Diag, Data_Exchange, FCB repeat
FAST_REPLY_KINDS = ("FDL status (SD1)", "Slave_Diag", "Data_Exchange", "repeat from the FCB cache")
REPLY_BUDGET = 1330      # every reply: 95 bit times at 12 Mbit/s on a 168 MHz Cortex-M4 (VPC3+)
LOOP_BUDGET = 500        # a main-loop section that can hold a reply off
POST_REPLY_BUDGET = 1330 # work after a reply: done before the next request can end (see above)
RAM_BUDGET = 6 * 1024
FLASH_BUDGET = 24 * 1024
RX_ISR_FUNCS = ("USART1_IRQHandler", "fdl_collect_slow", "fdl_collect_step", "rs485_uart_isr_other",
                "rs485_uart_rx_hand_over", "rx_take_telegram", "rx_queue_put", "rx_queue_full",
                "rx_queue_error", "rx_buf_index", "rx_char_with_error", "uart_rx_pending",
                "tx_fill", "tx_finish", "de_set")
SLOW_FUNCS = ("fdl_collect_slow", "fdl_collect_step", "rs485_uart_isr_other")


def ranges(s, names):
    return [(s[n][0], s[n][0] + s[n][1]) for n in names if n in s]


def inside(pc, rs):
    return any(a <= pc < b for a, b in rs)


def image_sizes(elf):
    out = subprocess.run(["arm-none-eabi-size", "-A", elf], capture_output=True, text=True).stdout
    sec = {}
    for l in out.splitlines():
        p = l.split()
        if len(p) == 3 and p[1].isdigit():
            sec[p[0]] = int(p[1])
    ram = sum(sec.get(n, 0) for n in (".data", ".bss", ".noinit", ".stack"))
    flash = sum(sec.get(n, 0) for n in (".isr_vector", ".text", ".rodata", ".ARM.exidx", ".data"))
    return ram, flash, sec


class Trace:
    """Walks the trace once and collects every figure."""

    def __init__(self, elf):
        s = symbols(elf)
        for need in ("fdl_station_reply_framed", "fdl_frame_in_place", "fdl_station_reply_rs",
                     "dp_slave_request", "dp_slave_rx_telegram", "svc_slave_diag",
                     "hook_prm_check", "hook_cfg_check", "hook_outputs", "dpv1_sap_request",
                     "svc_chk_cfg", "svc_data_exchange",
                     "conn_close", "rs485_uart_rx_hand_over", "rs485_wait_until",
                     "rs485_uart_transmit", "tx_fill", "USART1_IRQHandler"):
            if not any(n == need or n.startswith(need + ".") for n in s):
                sys.exit("reply_path_count: no function %s in the image; the tool needs updating"
                         % need)
        self.isr = s["USART1_IRQHandler"][0]
        self.isr_ranges = ranges(s, RX_ISR_FUNCS)
        self.slow_ranges = ranges(s, SLOW_FUNCS)
        self.hand_over = s["rs485_uart_rx_hand_over"][0]
        drain = s["rs485_uart_rx_drain"]
        self.drain = [(drain[0], drain[0] + drain[1])]
        self.tx_isr_work = ranges(s, ("tx_fill", "tx_finish"))
        self.post = None       # instructions after the last reply, until back in the drain
        self.post_work = []
        self.post_kind = None
        self.core_rx = s["dp_slave_rx_telegram"][0]
        self.backlog = 0
        self.wait = s["rs485_wait_until"]
        self.tx = s["rs485_uart_transmit"][0]
        self.dr_store = first_dr_store(elf, *s["tx_fill"])
        self.excl = ranges(s, ("SysTick_Handler", "timebase_tick", "board_leds_tick"))
        if "core_enter" not in s or "core_leave" not in s:
            sys.exit("reply_path_count: no core_enter/core_leave in the image; the tool needs "
                     "updating")
        self.masked = (s["core_enter"][0], s["core_leave"][0])
        self.interior, self.slow, self.results, self.passes = [], [], [], []
        self.isr_n = None      # instructions of the USART1 interrupt running
        self.isr_kind = None   # "interior", "slow" or "hand-over"
        self.reply = None      # the reply path being counted
        self.masked_at = None

    def end_isr(self):
        if self.isr_kind == "interior":
            self.interior.append(self.isr_n)
        elif self.isr_kind == "slow":
            self.slow.append(self.isr_n)
        self.isr_n = None

    def step(self, pc, handler, func):
        if not handler and pc == self.masked[0]:
            self.masked_at = 0
        elif self.masked_at is not None and not handler:
            if pc == self.masked[1]:
                self.passes.append(self.masked_at)
                self.masked_at = None
            else:
                self.masked_at += 1
        if inside(pc, self.excl):
            return
        if pc == self.isr:
            if self.isr_n is not None:
                self.end_isr()
            self.isr_n, self.isr_kind = 0, "interior"
        elif self.isr_n is not None and not inside(pc, self.isr_ranges):
            self.end_isr()
        if self.isr_n is not None:
            self.isr_n += 1
            if pc == self.hand_over:
                self.isr_kind = "hand-over"
                # a request whose reply was still being worked on got none (the transmitter
                # refuses a reply once the next request is in): the master, slowed by QEMU,
                # had sent again, and that work is not this reply's
                late = self.reply is not None and self.reply["telegrams"] > 0
                self.reply = {"n": self.isr_n, "funcs": set(), "wait": 0, "wait_last": 0,
                              "sent": False, "telegrams": 1 if late else 0}
            elif self.isr_kind == "interior" and inside(pc, self.slow_ranges):
                self.isr_kind = "slow"
        if self.post is not None and handler and self.isr_n is None:
            if inside(pc, self.drain):
                self.post_work.append((self.post, self.post_kind))
                self.post = None
            else:
                if not inside(pc, self.tx_isr_work):
                    self.post += 1
                return
        r = self.reply
        if r is None or not handler or pc == self.hand_over:
            return
        if not r["sent"] and inside(pc, self.tx_isr_work):
            return  # an earlier frame still going out (QEMU: all at once; a USART: per TXE)
        r["n"] += 1
        r["funcs"].add(func)
        if self.wait[0] <= pc < self.wait[0] + self.wait[1]:
            r["wait"] += 1
            r["wait_last"] = 1 if pc == self.wait[0] else r["wait_last"] + 1
        if pc == self.tx:
            r["sent"] = True
        if pc == self.core_rx:
            r["telegrams"] += 1
        if r["sent"] and pc == self.dr_store:
            n = r["n"] - r["wait"] + r["wait_last"]
            if r["telegrams"] > 1:
                # an earlier telegram was still queued (QEMU's pace let the master time out and
                # send again): its work is not this reply's
                self.backlog += 1
            else:
                self.results.append((classify_funcs(r["funcs"]), n))
            self.post = 0
            self.post_kind = classify_funcs(r["funcs"])
            self.reply = None


def report(t, caps, card):
    failures = []

    def check(what, value, budget):
        ok = value <= budget
        if not ok:
            failures.append("%s: %d > %d" % (what, value, budget))
        return "%d (budget %d%s)" % (value, budget, "" if ok else ", EXCEEDED")

    ps = pairs(caps)
    largest = max((len(rsp), kind) for kind, _, rsp in ps) if ps else (0, "")
    print("Real-time paths on the target (QEMU netduinoplus2, TCG single-step); %d replies in the "
          "trace, %d in the captures, the largest %d octets (%s); %d left out: another telegram "
          "was still queued before the request (the master, slowed by QEMU, had sent again)"
          % (len(t.results), len(ps), largest[0], largest[1], t.backlog))
    if not t.interior:
        sys.exit("reply_path_count: no interior character in the trace")
    print("per received character (USART1 interrupt, collector fast path): worst %s, median %d, "
          "%d characters" % (check("per character", max(t.interior), PER_CHAR_BUDGET),
                             sorted(t.interior)[len(t.interior) // 2], len(t.interior)))
    if t.slow:
        print("once per telegram (start delimiter, LE/LEr, SD2; the collector's slow path): worst "
              "%d, median %d, %d interrupts (one character time at 12 Mbit/s is 154)"
              % (max(t.slow), sorted(t.slow)[len(t.slow) // 2], len(t.slow)))
    core = defaultdict(list)
    for kind, n in t.results:
        core[kind].append(n)
    hdr = "| telegram → reply | n | instr. worst | instr. min | µs at %d MHz | bit times at " % MHZ
    hdr += " / ".join("%g M" % (b / 1e6) if b >= 1e6 else "%g k" % (b / 1e3) for b in BAUDS[:5])
    print(hdr + " | budget |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for kind in sorted(core, key=lambda k: -max(core[k])):
        w = max(core[kind])
        budget = FAST_REPLY_BUDGET if kind.startswith(FAST_REPLY_KINDS) else REPLY_BUDGET
        us = w / MHZ
        bits = " / ".join("%.1f" % (us * b / 1e6) for b in BAUDS[:5])
        print("| %s | %d | %d | %d | %.2f | %s | %s |" % (
            kind, len(core[kind]), w, min(core[kind]), us, bits,
            check("reply " + kind, w, budget).split(" (")[1].rstrip(")")))
    if t.post_work:
        worst = max(t.post_work)
        print("work after a reply, until the receive path is free for the next request: worst %s "
              "(after %s), median %d, %d replies"
              % (check("work after a reply", worst[0], POST_REPLY_BUDGET), worst[1],
                 sorted(t.post_work)[len(t.post_work) // 2][0], len(t.post_work)))
    if not t.passes:
        sys.exit("reply_path_count: no complete main-loop section in the trace")
    print("main-loop section holding PendSV off (core_enter .. core_leave): "
          "worst %s, median %d, %d sections"
          % (check("main-loop section", max(t.passes), LOOP_BUDGET),
             sorted(t.passes)[len(t.passes) // 2], len(t.passes)))
    if card:
        ram, flash, sec = image_sizes(card)
        print("card image: RAM %s (.data %d + .bss %d + .noinit %d + .stack %d), flash %s"
              % (check("RAM", ram, RAM_BUDGET), sec.get(".data", 0), sec.get(".bss", 0),
                 sec.get(".noinit", 0), sec.get(".stack", 0), check("flash", flash, FLASH_BUDGET)))
    for f in failures:
        print("reply_path_count: over budget: " + f, file=sys.stderr)
    return 1 if failures else 0


def main():
    args = sys.argv[1:]
    card = None
    if args[:1] == ["--card"]:
        card, args = args[1], args[2:]
    if len(args) < 3:
        sys.exit(__doc__.strip().splitlines()[-1])
    elf, trace, caps = args[0], args[1], args[2:]
    t = Trace(elf)
    line_re = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[([0-9a-f]+)/([0-9a-f]+)/[0-9a-f]+/[0-9a-f]+\] ?(\S*)")
    with open(trace, errors="replace") as f:
        for l in f:
            m = line_re.match(l)
            if m:
                t.step(int(m.group(2), 16), int(m.group(1), 16) & 1, m.group(3))
    return report(t, caps, card)


if __name__ == "__main__":
    sys.exit(main())
