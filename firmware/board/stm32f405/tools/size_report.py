#!/usr/bin/env python3
"""Flash and RAM of the image by module, from the GNU ld map file.

Every input section placed at a non-zero address is charged to the module its object came
from: the core libraries (dp_slave, dpv1, movilink, dfp21b, hal), the board files, newlib's
libc and libgcc, and the linker script's own (stack). Flash = .text + .rodata + vectors +
.data initialisers; RAM = .data + .bss + .noinit + the stack.
"""
import re
import sys

sec_re = re.compile(r"^ (\.[\w.$]+|COMMON)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
name_only_re = re.compile(r"^ (\.[\w.$]+|COMMON)\s*$")
cont_re = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")


def module_of(obj):
    m = re.search(r"libdfp_(\w+)\.a\(", obj)
    if m:
        return {"dp_slave": "dp_slave (FDL + DP-V0)", "dpv1": "dpv1 (MSAC1/2, DS47, I&M)",
                "movilink": "movilink (channel, client, SBus)", "dfp21b": "dfp21b personality",
                "hal": "hal (rates, names)"}.get(m.group(1), m.group(1))
    if "libc" in obj:
        return "newlib libc (memcpy, memset, ...)"
    if "libgcc" in obj:
        return "libgcc (EABI helpers)"
    m = re.search(r"/src/(\w+)\.c\.obj", obj)
    if m:
        return "board: " + m.group(1)
    return "other: " + obj.split("/")[-1]


def kind_of(sec):
    if sec.startswith((".text", ".rodata", ".isr_vector", ".ARM.exidx", ".ARM.extab", ".init", ".fini", ".glue",
                       ".vfp11", ".v4_bx", ".iplt", ".rel")):
        return "flash"
    if sec.startswith(".data"):
        return "data"
    if sec.startswith((".bss", "COMMON", ".noinit")):
        return "bss"
    return None


def main(path):
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    try:
        start = next(i for i, l in enumerate(lines) if l.startswith("Linker script and memory map"))
    except StopIteration:
        print("size_report: no memory map in " + path, file=sys.stderr)
        return 1
    table = {}
    pending = None
    stack = 0
    for l in lines[start:]:
        m = re.match(r"^\s+0x[0-9a-f]+\s+_stack_size = (0x[0-9a-f]+)", l)
        if m:
            stack = int(m.group(1), 16)
        m = sec_re.match(l)
        if m:
            sec, addr, size, obj = m.group(1), int(m.group(2), 16), int(m.group(3), 16), m.group(4)
        else:
            n = name_only_re.match(l)
            if n:
                pending = n.group(1)
                continue
            c = cont_re.match(l)
            if not (c and pending):
                pending = None
                continue
            sec, addr, size, obj = pending, int(c.group(1), 16), int(c.group(2), 16), c.group(3)
            pending = None
        k = kind_of(sec)
        if k is None or addr == 0 or size == 0 or "load address" in obj:
            continue
        row = table.setdefault(module_of(obj), {"flash": 0, "data": 0, "bss": 0})
        row[k] += size
    print("Size report by module (%s):" % path.split("/")[-1])
    print("  %-36s %8s %8s %8s %8s" % ("module", "code+ro", "data", "bss", "RAM"))
    tot = {"flash": 0, "data": 0, "bss": 0}
    core_flash = 0
    for mod in sorted(table, key=lambda m: -table[m]["flash"]):
        r = table[mod]
        print("  %-36s %8d %8d %8d %8d" % (mod, r["flash"], r["data"], r["bss"], r["data"] + r["bss"]))
        for k in tot:
            tot[k] += r[k]
        if mod.startswith(("dp_slave", "dpv1", "movilink", "dfp21b", "hal")):
            core_flash += r["flash"]
    print("  %-36s %8d %8d %8d %8d" % ("stack (linker script)", 0, 0, stack, stack))
    print("  %-36s %8d %8d %8d %8d" % ("total", tot["flash"], tot["data"], tot["bss"] + stack,
                                      tot["data"] + tot["bss"] + stack))
    print("  flash image = code+ro + data initialisers = %d B; RAM = %d B (%d B without the stack)"
          % (tot["flash"] + tot["data"], tot["data"] + tot["bss"] + stack, tot["data"] + tot["bss"]))
    dp = table.get("dp_slave (FDL + DP-V0)", {"flash": 0})["flash"]
    print("  VPC3+ for comparison: DP-V0 driver 4.7 kB code (here dp_slave %d B, which includes "
          "the FDL layer the ASIC does in hardware); demo image 8.4 kB ROM / 1.8 kB RAM (here %d B"
          " flash / %d B RAM for DP-V0 + DP-V1 + MOVILINK + SBus)" %
          (dp, tot["flash"] + tot["data"], tot["data"] + tot["bss"] + stack))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
