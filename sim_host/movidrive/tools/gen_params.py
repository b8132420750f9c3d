#!/usr/bin/env python3
"""Generate the emulated MOVIDRIVE's tables from the data in sim_host/movidrive/data/.

    gen_params.py            write src/movidrive_params.c, src/movidrive_names_table.c and
                             tools/wireshark/movidrive_params.lua
    gen_params.py --check    compare them with what the data gives; exit 1 and print a diff
                             for each file that differs

--data DIR and --root DIR (the repository) exist for tests of the generator itself.

Inputs (data/README.md describes the columns):
  parameters.csv     one row per parameter of the SEW parameter list (aliases included)
  faults.csv         fault number -> name
  unit_status.csv    unit status code (status word 1 high byte) -> name
  control_bits.csv   control word 1 basic block, bit -> meaning when set / when clear
  status_bits.csv    status word 1 basic block, the same

Rules for movidrive_params.c (the emulation's behaviour; see sim_host/movidrive/README.md):
- One entry per MOVILINK index, sorted. Where several rows share an index (P010..P013, P031 =
  P600, P160 = P162.n11, ...), the first row wins; the others are aliases, named in a comment.
- Flags from the SEW access attribute: RO -> read only, N -> non-volatile (EEPROM), R ->
  controller inhibit required, S -> writable despite P803. "Write volatile" is refused only where
  the volatile column says "no" (no row does today).
- min/max as given; a bound above INT32_MAX makes the parameter unsigned (stored as the same
  32-bit pattern, compared unsigned). No bound: no check.
- The first row's enumeration becomes a value mask when it covers exactly min..max (max < 32);
  values named RESERVED are not permitted.
- H0..H511 (11000 + n) are not table entries: one shared definition movidrive_ipos_def, from the
  H0 row.

movidrive_names_table.c (names for people) takes, per index, the first row's name and unit and the
first enumeration any row of that index carries (P031 has only a range, its alias P600 the list).
"""
import argparse
import csv
import difflib
import os
import re
import sys

INT32_MIN = -(1 << 31)
INT32_MAX = (1 << 31) - 1
UINT32_MAX = (1 << 32) - 1

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.normpath(os.path.join(HERE, "..", "data"))
DEFAULT_ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
OUT_PARAMS = "sim_host/movidrive/src/movidrive_params.c"
OUT_NAMES = "sim_host/movidrive/src/movidrive_names_table.c"
OUT_LUA = "tools/wireshark/movidrive_params.lua"
P_NUMBER = re.compile(r"P(\d{3})(\.[A-Za-z0-9_.()\[\]]+)?$")
H_NUMBER = re.compile(r"H(\d+)$")


class DataError(Exception):
    pass


def parse_int(text):
    text = text.strip()
    if text == "":
        return None
    return int(text, 0)


def to_int32(v):
    return v - (1 << 32) if v > INT32_MAX else v


def read_csv(path):
    try:
        with open(path, encoding="utf-8", newline="") as f:
            return list(csv.DictReader(f))
    except OSError as e:
        raise DataError(f"{path}: {e.strerror}") from e


def parse_enum(text, where):
    """'0=OFF|1=ON' -> [(0, 'OFF'), (1, 'ON')] in the order given."""
    if text.strip() == "":
        return []
    out = []
    seen = set()
    for item in text.split("|"):
        value, sep, label = item.partition("=")
        try:
            v = int(value.strip(), 0)
        except ValueError:
            v = None
        if not sep or v is None or label.strip() == "":
            raise DataError(f"{where}: enumeration item {item!r} is not VALUE=TEXT")
        if v in seen:
            raise DataError(f"{where}: value {v} named twice")
        seen.add(v)
        out.append((v, label.strip()))
    return out


def load_params(data):
    path = os.path.join(data, "parameters.csv")
    rows = read_csv(path)
    need = {"p_number", "index", "name", "unit", "scale_exp", "min", "max", "default", "access",
            "volatile", "quantity", "conversion", "enum", "note"}
    if not rows or need - set(rows[0]):
        raise DataError(f"{path}: columns {sorted(need - set(rows[0] if rows else {}))} missing")
    for n, r in enumerate(rows, start=2):
        where = f"{path}:{n} ({r['p_number']})"
        if not (P_NUMBER.match(r["p_number"]) or H_NUMBER.match(r["p_number"])):
            raise DataError(f"{where}: P-number not understood")
        try:
            r["index"] = int(r["index"])
            r["scale_exp"] = int(r["scale_exp"])
            r["lo"] = parse_int(r["min"])
            r["hi"] = parse_int(r["max"])
            r["def"] = parse_int(r["default"]) or 0
            r["quantity"] = int(r["quantity"] or 0)
            r["conversion"] = int(r["conversion"] or 0)
        except ValueError as e:
            raise DataError(f"{where}: {e}") from e
        r["enums"] = parse_enum(r["enum"], where)
        r["where"] = where
    return rows


def flags_of(r):
    attrs = set(r["access"].split("/"))
    unknown = attrs - {"RO", "RW", "N", "R", "S"}
    if unknown or ("RO" in attrs) == ("RW" in attrs):
        raise DataError(f"{r['where']}: access attribute {r['access']!r} not understood")
    flags = []
    if "RO" in attrs:
        flags.append("MOVIDRIVE_PF_READ_ONLY")
    if "N" in attrs:
        flags.append("MOVIDRIVE_PF_NON_VOLATILE")
    if "R" in attrs:
        flags.append("MOVIDRIVE_PF_INHIBIT_REQUIRED")
    if "S" in attrs:
        flags.append("MOVIDRIVE_PF_LOCK_EXEMPT")
    if r["volatile"].strip().lower().startswith("no") and "RO" not in attrs:
        flags.append("MOVIDRIVE_PF_NO_VOLATILE")
    lo, hi = r["lo"], r["hi"]
    unsigned = hi is not None and hi > INT32_MAX
    if unsigned and (lo is None or lo < 0 or hi > UINT32_MAX):
        raise DataError(f"{r['where']}: range {lo}..{hi} fits neither int32 nor uint32")
    if lo is not None:
        flags.append("MOVIDRIVE_PF_HAS_MIN")
    if hi is not None:
        flags.append("MOVIDRIVE_PF_HAS_MAX")
    if unsigned:
        flags.append("MOVIDRIVE_PF_UNSIGNED")
    return flags


def build(data):
    rows = load_params(data)
    first = {}
    aliases = {}
    enums = {}
    ipos = None
    for r in rows:
        if H_NUMBER.match(r["p_number"]):
            if ipos is None:
                ipos = r
            continue
        i = r["index"]
        if i in first:
            aliases.setdefault(i, []).append(r)
        else:
            first[i] = r
        if r["enums"] and i not in enums:
            enums[i] = r["enums"]
    if ipos is None or ipos["index"] != 11000 or "RW" not in ipos["access"].split("/"):
        raise DataError("the H0 row (index 11000, RW) is missing")
    if len(first) > 512:
        raise DataError(f"{len(first)} parameters, MOVIDRIVE_MAX_PARAMS is 512")
    seen_p = {}
    for r in rows:
        key = r["p_number"].upper()
        if key in seen_p:
            raise DataError(f"{r['where']}: P-number also in {seen_p[key]}")
        seen_p[key] = r["where"]
    table = []
    for i in sorted(first):
        r = first[i]
        flags = flags_of(r)
        for a in aliases.get(i, []):
            flags_of(a)
        lo, hi = r["lo"], r["hi"]
        mask = 0
        if ("MOVIDRIVE_PF_READ_ONLY" not in flags and lo is not None and hi is not None
                and r["enums"]):
            values = {v for v, _ in r["enums"]}
            if min(values) == lo and max(values) == hi and hi < 32:
                for v, label in r["enums"]:
                    if not label.upper().startswith("RESERVED"):
                        mask |= 1 << v
        table.append(dict(row=r, flags=flags, mask=mask,
                          lo=to_int32(lo) if lo is not None else 0,
                          hi=to_int32(hi) if hi is not None else 0,
                          default=to_int32(r["def"]), aliases=aliases.get(i, []),
                          enums=enums.get(i, [])))
    return table, ipos, rows


def c_int(v, unsigned=False):
    if v == INT32_MIN:
        return "INT32_MIN"
    if unsigned and v < 0:
        return f"{v} /* {v + (1 << 32)}u */"
    return str(v)


def c_str(s):
    out = ['"']
    for b in s.encode("utf-8"):
        ch = chr(b)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 0x20 <= b < 0x7F:
            out.append(ch)
        else:
            out.append(f"\\{b:03o}")  # octal: a hex escape would swallow a following [0-9A-F]
    out.append('"')
    return "".join(out)


def comment(s):
    return s.replace("*/", "* /")


HEADER = ("/* GENERATED by sim_host/movidrive/tools/gen_params.py from sim_host/movidrive/data/.\n"
          " * Do not edit: change the data and re-run the generator. The test\n"
          " * movidrive_params_generated fails when this file and the data disagree.")


def render_params(data):
    table, ipos, _ = build(data)
    out = []
    w = out.append
    w(HEADER)
    w(" *")
    w(" * Per entry: index, min, max, default (raw bus values), quantity index, conversion index,")
    w(" * flags, enumeration mask (bit n set = value n defined; 0 = no enumeration known). */")
    w('#include "movidrive_params.h"')
    w("")
    w("#include <stdint.h>")
    w("")
    w("const movidrive_param_def_t movidrive_params[] = {")
    for e in table:
        r = e["row"]
        flags = " | ".join(e["flags"]) if e["flags"] else "0"
        text = f"{r['p_number']} {r['name']}"
        if e["aliases"]:
            text += f" (also {', '.join(a['p_number'] for a in e['aliases'])})"
        w(f"    /* {comment(text)} */")
        if r["note"]:
            w(f"    /* {comment(r['note'])} */")
        u = "MOVIDRIVE_PF_UNSIGNED" in e["flags"]
        w(f"    {{{r['index']}, {c_int(e['lo'], u)}, {c_int(e['hi'], u)}, "
          f"{c_int(e['default'], u)}, {r['quantity']}, {r['conversion']}, {flags}, "
          f"0x{e['mask']:08X}u}},")
    w("};")
    w("")
    w("const size_t movidrive_params_count = "
      "sizeof movidrive_params / sizeof movidrive_params[0];")
    w("")
    w(f"/* {comment(ipos['p_number'])}: {comment(ipos['name'])}.")
    w(" * H0..H511 at 11000 + n: int32, read/write, write volatile allowed, kept in EEPROM by a")
    w(" * (non-volatile) write. */")
    w("const movidrive_param_def_t movidrive_ipos_def = {11000, INT32_MIN, INT32_MAX, 0, 0, 0,")
    w("                                    "
      "MOVIDRIVE_PF_NON_VOLATILE | MOVIDRIVE_PF_HAS_MIN | MOVIDRIVE_PF_HAS_MAX, 0u};")
    return "\n".join(out) + "\n"


def p_sort_key(r, pos):
    m = P_NUMBER.match(r["p_number"])
    return (int(m.group(1)), pos)


def load_codes(data, name, key):
    path = os.path.join(data, name)
    out = []
    for n, r in enumerate(read_csv(path), start=2):
        try:
            code = int(r[key])
        except (KeyError, ValueError) as e:
            raise DataError(f"{path}:{n}: {key} not a number") from e
        if not 0 <= code <= 255 or r.get("name", "").strip() == "":
            raise DataError(f"{path}:{n}: {key} 0..255 and a name expected")
        out.append((code, r["name"].strip()))
    codes = [c for c, _ in out]
    if len(set(codes)) != len(codes):
        raise DataError(f"{path}: a {key} is listed twice")
    return sorted(out)


def load_bits(data, name):
    path = os.path.join(data, name)
    bits = {}
    for n, r in enumerate(read_csv(path), start=2):
        try:
            b = int(r["bit"])
        except (KeyError, ValueError) as e:
            raise DataError(f"{path}:{n}: bit not a number") from e
        if not 0 <= b <= 7 or b in bits or r.get("set", "").strip() == "":
            raise DataError(f"{path}:{n}: bit 0..7, once each, with a text when set")
        bits[b] = (r["set"].strip(), r.get("clear", "").strip())
    if sorted(bits) != list(range(8)):
        raise DataError(f"{path}: bits 0..7 expected")
    return [bits[b] for b in range(8)]


def render_names(data):
    table, _, rows = build(data)
    by_index = {e["row"]["index"]: e for e in table}
    order = sorted(table, key=lambda e: p_sort_key(e["row"], rows.index(e["row"])))
    faults = load_codes(data, "faults.csv", "fault")
    status = load_codes(data, "unit_status.csv", "code")
    cw = load_bits(data, "control_bits.csv")
    sw = load_bits(data, "status_bits.csv")
    out = []
    w = out.append
    w(HEADER + " */")
    w('#include "movidrive_names_table.h"')
    w("")
    w("#include <stddef.h>")
    w("#include <stdint.h>")
    w("")
    w("/* Enumerations, shared between parameters that use the same list. */")
    enum_names = {}
    for e in order:
        key = tuple(e["enums"])
        if not key or key in enum_names:
            continue
        name = f"movidrive_enum_{len(enum_names)}"
        enum_names[key] = name
        w(f"static const movidrive_enum_text_t {name}[] = {{")
        for v, label in key:
            w(f"    {{{v}, {c_str(label)}}},")
        w("};")
    w("")
    w("/* Sorted by P-number; one row per MOVILINK index (the first of the list). */")
    w("const movidrive_param_info_t movidrive_param_infos[] = {")
    for e in order:
        r = e["row"]
        key = tuple(e["enums"])
        en = f"{enum_names[key]}, {len(key)}" if key else "NULL, 0"
        ro = "MOVIDRIVE_PF_READ_ONLY" in e["flags"]
        nv = "MOVIDRIVE_PF_NON_VOLATILE" in e["flags"]
        inh = "MOVIDRIVE_PF_INHIBIT_REQUIRED" in e["flags"]
        w(f"    {{{c_str(r['p_number'])}, {r['index']}, {c_str(r['name'])}, {c_str(r['unit'])}, "
          f"{r['scale_exp']}, {en}, {str(ro).lower()}, {str(nv).lower()}, {str(inh).lower()}}},")
    w("};")
    w("")
    w("const size_t movidrive_param_infos_count = "
      "sizeof movidrive_param_infos / sizeof movidrive_param_infos[0];")
    w("")
    w("/* Positions in movidrive_param_infos, sorted by index (for the binary search by index). */")
    w("const uint16_t movidrive_param_infos_by_index[] = {")
    where = {id(e["row"]): n for n, e in enumerate(order)}
    line = "   "
    for i in sorted(by_index):
        item = f" {where[id(by_index[i]['row'])]},"
        if len(line) + len(item) > 100:
            w(line)
            line = "   "
        line += item
    w(line)
    w("};")
    w("")
    w("/* The other P-numbers of an index (P011 = P010's index, P600 = P031's ...). */")
    w("const movidrive_param_alias_t movidrive_param_aliases[] = {")
    for e in order:
        for a in e["aliases"]:
            w(f"    {{{c_str(a['p_number'])}, {a['index']}}},")
    w("};")
    w("")
    w("const size_t movidrive_param_aliases_count = "
      "sizeof movidrive_param_aliases / sizeof movidrive_param_aliases[0];")
    w("")
    for name, codes in (("movidrive_fault_names", faults), ("movidrive_unit_status_names", status)):
        w(f"const movidrive_code_name_t {name}[] = {{")
        for c, text in codes:
            w(f"    {{{c}, {c_str(text)}}},")
        w("};")
        w("")
        w(f"const size_t {name}_count = sizeof {name} / sizeof {name}[0];")
        w("")
    for name, bits in (("movidrive_control_bits", cw), ("movidrive_status_bits", sw)):
        w(f"const movidrive_bit_text_t {name}[8] = {{")
        for s, c in bits:
            w(f"    {{{c_str(s)}, {c_str(c)}}},")
        w("};")
        w("")
    return "\n".join(out).rstrip("\n") + "\n"


def lua_str(s):
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def render_lua(data):
    table, _, _ = build(data)
    out = ["-- GENERATED by sim_host/movidrive/tools/gen_params.py from sim_host/movidrive/data/.",
           "-- Do not edit: change the data and re-run the generator. profibus.lua loads this file",
           "-- to name MOVILINK indices; it falls back to bare numbers without it.",
           "return {"]
    for e in table:
        r = e["row"]
        out.append(f"  [{r['index']}] = {lua_str(r['p_number'] + ' ' + r['name'])},")
    out.append("}")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=DEFAULT_DATA, help="the data directory")
    ap.add_argument("--root", default=DEFAULT_ROOT, help="the repository the outputs belong to")
    ap.add_argument("--check", action="store_true", help="compare instead of writing")
    a = ap.parse_args()
    try:
        outputs = [(OUT_PARAMS, render_params(a.data)), (OUT_NAMES, render_names(a.data)),
                   (OUT_LUA, render_lua(a.data))]
    except DataError as e:
        print(f"gen_params.py: {e}", file=sys.stderr)
        return 2
    status = 0
    for rel, text in outputs:
        path = os.path.join(a.root, rel)
        if not a.check:
            with open(path, "w", encoding="utf-8", newline="\n") as f:
                f.write(text)
            continue
        try:
            with open(path, encoding="utf-8") as f:
                committed = f.read()
        except OSError as e:
            print(f"{rel}: {e.strerror}")
            status = 1
            continue
        if committed == text:
            print(f"{rel}: matches the data")
            continue
        sys.stdout.writelines(difflib.unified_diff(
            committed.splitlines(True), text.splitlines(True), rel, "generated"))
        print(f"{rel} differs from the data: re-run {sys.argv[0]}")
        status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
