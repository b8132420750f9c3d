#!/usr/bin/env python3
"""Stack report for the STM32F405 image: worst call chain per entry point, no recursion, no
dynamic stack, no heap.

Input: the .ci files GCC writes with -fcallgraph-info=su (one VCG graph per translation unit:
nodes with their frame size, direct call edges, and edges to "__indirect_call" labelled with the
call site). Indirect calls are resolved by name: the call site's source text names the member
called (`s->cfg.uart.ops->transmit(`), and every `.member = function` initialiser or assignment
in the sources says which functions can sit in such a member. An indirect call that cannot be
resolved that way fails the report, as do recursion, a dynamic frame (VLA, alloca) and any heap
function linked into the image.

Total: thread chain (reset -> main -> ...) + the worst chain of every interrupt that can nest on
top of it (SysTick, USART1, PendSV, CAN1 RX0; fault handlers end the program) + one basic exception
frame (8 words + 4 bytes of alignment = 36 bytes) per nesting level. Basic, because the FPU stays
off (startup.c) and the image holds no floating-point instruction, which this report checks (an
FP instruction fails it: with the FPU on, each frame would take 108 bytes). Library leaves that have no .ci
(memcpy, memset, memcmp, EABI helpers from newlib/libgcc) are charged LIB_LEAF bytes each.
"""
import argparse
import glob
import os
import re
import subprocess
import sys

LIB_LEAF = 32
EXC_FRAME = 36
ENTRIES_THREAD = ["board_reset_c"]
ENTRIES_IRQ = ["SysTick_Handler", "USART1_IRQHandler", "PendSV_Handler", "CAN1_RX0_IRQHandler"]
ENTRIES_FAULT = ["board_fault_entry"]
# Indirect calls the member-name rule cannot see or would over-approximate, stated by hand:
# (caller, member) -> callees (static functions as "file.c:name"). Keep this list short.
OVERRIDES = {
    # ml_client_request(..., done, ...): the three callers pass these
    ("fail_hardware", "done"): ["ds47.c:on_done", "dfp21b.c:on_status", "movilink_channel.c:on_done"],
    ("ml_client_response", "done"): ["ds47.c:on_done", "dfp21b.c:on_status",
                                     "movilink_channel.c:on_done"],
    # dfp21b's own event hook calls the board's event callback, not itself
    ("hook_event", "event"): ["main.c:card_event"],
}
HEAP = {"malloc", "free", "calloc", "realloc", "_sbrk", "_malloc_r", "_free_r", "sbrk"}

node_re = re.compile(r'^node: \{ title: "([^"]+)" label: "([^"]*)"')
edge_re = re.compile(r'^edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"(?: label: "([^"]*)")?')


def load_graph(root, image):
    nodes = {}   # title -> (bytes, dynamic, file)
    edges = {}   # title -> list of (target, site)
    files = []
    for ci in glob.glob(os.path.join(root, "**", "*.ci"), recursive=True):
        parts = ci.split(os.sep)
        # the board objects of other images are not in this one
        if any(p.endswith(".dir") and p.startswith("dfp21b-stm32f405") and p != image + ".dir"
               for p in parts):
            continue
        files.append(ci)
        for line in open(ci, encoding="utf-8", errors="replace"):
            m = node_re.match(line)
            if m:
                title, label = m.group(1), m.group(2)
                fields = label.split("\\n")
                size = None
                dynamic = False
                for f in fields[1:]:
                    mm = re.match(r"(\d+) bytes \((\w+)", f)
                    if mm:
                        size = int(mm.group(1))
                        dynamic = mm.group(2) != "static"
                if size is not None or title not in nodes:
                    if size is not None or title not in nodes:
                        nodes[title] = (size, dynamic, ci)
                continue
            m = edge_re.match(line)
            if m:
                edges.setdefault(m.group(1), []).append((m.group(2), m.group(3)))
    return nodes, edges, files


def member_targets(src_roots, known):
    """member name -> set of function titles assigned to it anywhere in the sources."""
    short = {}
    for t in known:
        short.setdefault(t.split(":")[-1], set()).add(t)
    assign = re.compile(r"\.(\w+)\s*=\s*&?(\w+)\s*[,;}\n]")
    out = {}
    for root in src_roots:
        for path in glob.glob(os.path.join(root, "**", "*.[ch]"), recursive=True):
            text = open(path, encoding="utf-8", errors="replace").read()
            for m in assign.finditer(text):
                fn = m.group(2)
                if fn in short:
                    out.setdefault(m.group(1), set()).update(short[fn])
    return out


def call_member(site):
    """'file:line:col' of an indirect call -> the member name being called."""
    m = re.match(r"(.*):(\d+):(\d+)$", site or "")
    if not m:
        return None
    path, line, col = m.group(1), int(m.group(2)), int(m.group(3))
    try:
        text = open(path, encoding="utf-8", errors="replace").read().split("\n")
    except OSError:
        return None
    # A member call on the line (`->transmit(`, `.now(`): the location GCC gives may be that of
    # an enclosing inlined call, so look at the whole line first.
    calls = re.findall(r"(?:\.|->)(\w+)\s*\(", text[line - 1])
    if len(set(calls)) == 1:
        return calls[0]
    s = text[line - 1][col - 1:]
    # the callee expression runs up to the first '(' that opens the argument list
    depth = 0
    expr = ""
    for ch in s:
        if ch == "(" and depth == 0 and expr and (expr[-1].isalnum() or expr[-1] in "_)"):
            break
        expr += ch
    names = re.findall(r"[A-Za-z_]\w*", expr)
    return names[-1] if names else None


def fp_instructions(elf):
    """VFP/FPU instructions in the image: in Thumb-2 every one of them, and no integer
    instruction, has a mnemonic that starts with 'v'."""
    out = subprocess.run(["arm-none-eabi-objdump", "-d", elf], capture_output=True, text=True,
                         check=True).stdout
    return [l.strip() for l in out.splitlines() if re.match(r"\s*[0-9a-f]+:\s.*\tv[a-z]", l)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--elf", required=True)
    ap.add_argument("--root", required=True, help="cross build directory")
    ap.add_argument("--image", required=True)
    ap.add_argument("--stack-size", type=int, required=True)
    ap.add_argument("--src", action="append", default=[])
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args()
    src = a.src or [os.path.abspath(os.path.join(os.path.dirname(__file__), "../../../.."))]
    src_dirs = [os.path.join(src[0], d) for d in ("dp_slave", "dpv1", "movilink", "firmware", "hal")]

    nm = subprocess.run(["arm-none-eabi-nm", a.elf], capture_output=True, text=True, check=True)
    linked = {l.split()[-1] for l in nm.stdout.splitlines() if l.strip()}
    errors = []
    heap = sorted(HEAP & linked)
    if heap:
        errors.append("heap functions linked: " + ", ".join(heap))
    fp = fp_instructions(a.elf)
    if fp:
        errors.append("floating-point instructions in the image (the FPU is off; exception "
                      "frames would be 108 B with it on): " + "; ".join(fp[:3]))

    nodes, edges, _ = load_graph(a.root, a.image)
    members = member_targets(src_dirs, [t for t in nodes if nodes[t][0] is not None])
    short_linked = lambda t: t.split(":")[-1].split(".")[0] in linked

    unresolved = []
    nulls = set()
    memo = {}
    on_path = []

    def callees(t):
        out = []
        for tgt, site in edges.get(t, []):
            if tgt == "__indirect_call":
                mem = call_member(site)
                key = (t.split(":")[-1], mem)
                if key in OVERRIDES:
                    cands = set()
                    for o in OVERRIDES[key]:
                        cands |= {n for n in nodes if n == o or
                                  (n.endswith("/" + o) and nodes[n][0] is not None)}
                else:
                    cands = members.get(mem, set()) if mem else set()
                    if mem and mem not in members:
                        # no function of the image is ever stored in this member (an optional
                        # hook left NULL here: nvm ops, the test-only app hooks): no call
                        nulls.add("%s (%s)" % (mem, t.split(":")[-1]))
                        continue
                cands = {c for c in cands if short_linked(c)}
                if not cands:
                    unresolved.append("%s (%s) in %s" % (site, mem, t.split(":")[-1]))
                out.extend((c, "*" + (mem or "?")) for c in sorted(cands))
            else:
                out.append((tgt, ""))
        return out

    def worst(t):
        if t in memo:
            return memo[t]
        if t in on_path:
            cyc = on_path[on_path.index(t):] + [t]
            errors.append("recursion: " + " -> ".join(x.split(":")[-1] for x in cyc))
            return (0, [t])
        size, dynamic, _ = nodes.get(t, (None, False, None))
        if size is None:
            memo[t] = (LIB_LEAF, [t + " (library, %d assumed)" % LIB_LEAF])
            return memo[t]
        if dynamic:
            errors.append("dynamic stack frame: " + t)
        on_path.append(t)
        best = (0, [])
        for c, how in callees(t):
            w = worst(c)
            if w[0] > best[0]:
                best = (w[0], [("via %s: " % how if how else "") + w[1][0]] + w[1][1:])
        on_path.pop()
        memo[t] = (size + best[0], ["%s (%d)" % (t.split(":")[-1], size)] + best[1])
        return memo[t]

    def show(name, res):
        print("  %-22s %5d B  %s" % (name, res[0], " -> ".join(res[1])))

    print("Stack report (%s, -fstack-usage/-fcallgraph-info, indirect calls resolved by member"
          " name):" % a.image)
    total = 0
    for e in ENTRIES_THREAD:
        r = worst(e)
        show(e, r)
        total += r[0]
    for e in ENTRIES_IRQ:
        r = worst(e)
        show(e, r)
        total += r[0] + EXC_FRAME
    for e in ENTRIES_FAULT:
        r = worst(e)
        show(e + " (ends the run)", r)
    if nulls:
        print("  hooks never set in this image (indirect calls that cannot happen): " +
              ", ".join(sorted(nulls)))
    for u in sorted(set(unresolved)):
        errors.append("unresolved indirect call at " + u)
    print("  worst case: thread + every interrupt nested (+%d B exception frame each) = %d B of "
          "%d B stack" % (EXC_FRAME, total, a.stack_size))
    if total > a.stack_size:
        errors.append("worst case %d B exceeds the %d B stack" % (total, a.stack_size))
    print("\n  recursion: %s; dynamic frames: %s; heap: %s" % (
        "none" if not any(e.startswith("recursion") for e in errors) else "FOUND",
        "none" if not any(e.startswith("dynamic") for e in errors) else "FOUND",
        "none" if not heap else ", ".join(heap)))
    for e in errors:
        print("stack_report: error: " + e, file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
