#!/usr/bin/env python3
"""Generate the emulated MOVIDRIVE's parameter table (sim_host/movidrive/src/md_params.c).

Inputs: shared/spec/movidrive-parameters.csv (index, min, max, default, ro/rw, volatile_allowed)
and movidrive-parameters-extra.csv (PNO quantity/conversion index, the raw SEW access flags,
value range / enumeration text), row by row the same parameters (the extra file lacks the two
IPOS rows H0/H511).

    gen_params.py PARAMS_CSV EXTRA_CSV -o md_params.c      write the table
    gen_params.py PARAMS_CSV EXTRA_CSV --check md_params.c  compare, exit 1 and print a diff if
                                                            different, 77 if a CSV is missing

Rules (see sim_host/movidrive/README.md):
- One entry per MOVILINK index, sorted. Where several rows share an index (P010..P013, P031 =
  P600, P160 = P162.n11, ...), the first row in the CSV wins; the others are listed as aliases
  in a comment.
- Flags from the SEW access attribute (movidrive.md 1.3, S2 p.67): RO -> read only, N ->
  non-volatile (EEPROM), R -> controller inhibit required, S -> writable despite P803.
  "Write volatile" is refused only where volatile_allowed says "no..." (no row does today).
- min/max from the CSV; a bound above INT32_MAX makes the parameter unsigned (stored as the
  same 32-bit pattern, compared unsigned). No bound in the CSV: no check.
- Enumerations: "n = TEXT | ..." in value_range_or_enum (or "See menu no. X or index Y",
  resolved through Y). Used as a value mask only when it covers the CSV's min and max; values
  named RESERVED are not permitted. Fix-up: P830 (8609) lists 7 twice, movidrive.md 3.6 says the
  first "7" is 6 = EMERG. STOP/WARNG.
- Default override: P076 (8300) firmware basic unit = 0x311C7289 = 823947913 (S1, DFP21B
  manual 6.3 example read of index 8300).
- H0..H511 (11000 + n) are not in the table: one shared definition md_ipos_def (int32, read/write,
  write volatile allowed, kept in EEPROM) taken from the H0 row.
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

DEFAULT_OVERRIDES = {
    8300: (0x311C7289, "S1 6.3: index 8300 reads 0x311C7289 (firmware 823 947 9.13)"),
}
ENUM_FIXUPS = {
    8609: ({6}, "movidrive.md 3.6: the A list prints 7 twice; 6 = EMERG. STOP/WARNG"),
}
ENUM_TOKEN = re.compile(r"(?:^|(?<=[\s|/]))(\d+)\s*=\s")
SEE_REF = re.compile(r"See menu no\.\s*(\d+)\s+or index\s+(\d+)")


def is_ipos(p_number):
    return p_number.startswith("H")


def parse_int(text):
    text = text.strip()
    if text == "":
        return None
    return int(text, 0)


def enum_values(text):
    """{value: label} of an enumeration text, or None when the text is a range/other."""
    if re.search(r"\d\s*[–-]\s*-?\d.*step", text):
        return None
    labels = {}
    matches = list(ENUM_TOKEN.finditer(text))
    for i, m in enumerate(matches):
        end = matches[i + 1].start() if i + 1 < len(matches) else len(text)
        label = text[m.end():end].strip(" |/")
        labels.setdefault(int(m.group(1)), label)
    return labels or None


def load(params_csv, extra_csv):
    with open(params_csv, encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    with open(extra_csv, encoding="utf-8", newline="") as f:
        extra = {r["p_number"]: r for r in csv.DictReader(f)}
    return rows, extra


def c_int(v, unsigned=False):
    if v == INT32_MIN:
        return "INT32_MIN"
    if unsigned and v < 0:
        return f"{v} /* {v + (1 << 32)}u */"
    return str(v)


def to_int32(v):
    return v - (1 << 32) if v > INT32_MAX else v


def build(params_csv, extra_csv):
    rows, extra = load(params_csv, extra_csv)
    enum_text = {}
    for r in rows:
        x = extra.get(r["p_number"])
        if x is not None:
            enum_text.setdefault(int(r["index"]), x["value_range_or_enum"])

    def resolve_enum(index, depth=0):
        """(labels, index the enumeration text belongs to)"""
        text = enum_text.get(index, "")
        m = SEE_REF.search(text)
        if m and depth < 4:
            return resolve_enum(int(m.group(2)), depth + 1)
        return enum_values(text), index

    entries = {}
    order = []
    aliases = {}
    ipos = None
    for r in rows:
        p = r["p_number"]
        if is_ipos(p):
            if ipos is None:
                ipos = r
            continue
        index = int(r["index"])
        if index in entries:
            aliases.setdefault(index, []).append(p)
            continue
        x = extra.get(p)
        if x is None:
            raise SystemExit(f"{p}: no row in {extra_csv}")
        if int(x["index"]) != index:
            raise SystemExit(f"{p}: index {index} here, {x['index']} in the extra CSV")
        attrs = set(x["sew_access_attr"].split("/"))
        unknown = attrs - {"RO", "RW", "N", "R", "S"}
        if unknown or ("RO" in attrs) == ("RW" in attrs):
            raise SystemExit(f"{p}: access attribute {x['sew_access_attr']!r} not understood")
        if ("RO" in attrs) != (r["access"] == "ro"):
            raise SystemExit(f"{p}: {x['sew_access_attr']} vs access {r['access']}")
        flags = []
        if "RO" in attrs:
            flags.append("MD_PF_READ_ONLY")
        if "N" in attrs:
            flags.append("MD_PF_NON_VOLATILE")
        if "R" in attrs:
            flags.append("MD_PF_INHIBIT_REQUIRED")
        if "S" in attrs:
            flags.append("MD_PF_LOCK_EXEMPT")
        if r["volatile_allowed"].strip().lower().startswith("no") and "RO" not in attrs:
            flags.append("MD_PF_NO_VOLATILE")
        lo = parse_int(r["min"])
        hi = parse_int(r["max"])
        unsigned = hi is not None and hi > INT32_MAX
        if unsigned and (lo is None or lo < 0 or hi > UINT32_MAX):
            raise SystemExit(f"{p}: range {lo}..{hi} fits neither int32 nor uint32")
        if lo is not None:
            flags.append("MD_PF_HAS_MIN")
        if hi is not None:
            flags.append("MD_PF_HAS_MAX")
        if unsigned:
            flags.append("MD_PF_UNSIGNED")
        default = parse_int(r["default"]) or 0
        note = ""
        if index in DEFAULT_OVERRIDES:
            default, note = DEFAULT_OVERRIDES[index]
        mask = 0
        enum_note = ""
        if "RO" not in attrs and lo is not None and hi is not None:
            labels, base = resolve_enum(index)
            if labels is not None:
                values = set(labels)
                fix = ENUM_FIXUPS.get(base)
                if fix:
                    values |= fix[0]
                    enum_note = fix[1]
                if min(values) == lo and max(values) == hi and hi < 32:
                    for v, label in labels.items():
                        if label.upper().startswith("RESERVED"):
                            values.discard(v)
                    for v in values:
                        mask |= 1 << v
        entries[index] = dict(
            p=p, name=r["name"], index=index,
            lo=to_int32(lo) if lo is not None else 0,
            hi=to_int32(hi) if hi is not None else 0,
            default=to_int32(default),
            quantity=int(x["quantity_index"]), conversion=int(x["conversion_index"]),
            flags=flags, mask=mask, note=note, enum_note=enum_note)
        order.append(index)
    if ipos is None or int(ipos["index"]) != 11000 or ipos["access"] != "rw":
        raise SystemExit("the H0 row (index 11000, rw) is missing")
    if len(entries) > 512:
        raise SystemExit(f"{len(entries)} parameters, MD_MAX_PARAMS is 512")
    return [entries[i] for i in sorted(entries)], aliases, ipos


def render(params_csv, extra_csv):
    table, aliases, ipos = build(params_csv, extra_csv)
    out = []
    w = out.append
    w("/* GENERATED by sim_host/movidrive/tools/gen_params.py from movidrive-parameters.csv and")
    w(" * movidrive-parameters-extra.csv (shared/spec). Do not edit; re-run the generator. The test")
    w(" * movidrive_params_generated checks that this file matches the CSVs.")
    w(" *")
    w(" * Per entry: index, min, max, default (raw bus values), quantity index, conversion index,")
    w(" * flags, enumeration mask (bit n set = value n defined; 0 = no enumeration known). */")
    w('#include "md_params.h"')
    w("")
    w("#include <stdint.h>")
    w("")
    w("const md_param_def_t md_params[] = {")
    for e in table:
        flags = " | ".join(e["flags"]) if e["flags"] else "0"
        comment = f"{e['p']} {e['name']}"
        if e["index"] in aliases:
            comment += f" (also {', '.join(aliases[e['index']])})"
        comment = comment.replace("*/", "* /")
        w(f"    /* {comment} */")
        if e["note"]:
            w(f"    /* default: {e['note']} */")
        if e["enum_note"]:
            w(f"    /* values: {e['enum_note']} */")
        u = "MD_PF_UNSIGNED" in e["flags"]
        w(f"    {{{e['index']}, {c_int(e['lo'], u)}, {c_int(e['hi'], u)}, {c_int(e['default'], u)}, "
          f"{e['quantity']}, {e['conversion']}, {flags}, 0x{e['mask']:08X}u}},")
    w("};")
    w("")
    w("const size_t md_params_count = sizeof md_params / sizeof md_params[0];")
    w("")
    w(f"/* {ipos['p_number']}: {ipos['name']}.")
    w(" * H0..H511 at 11000 + n: int32, read/write, write volatile allowed, kept in EEPROM by a")
    w(" * (non-volatile) write. */")
    w("const md_param_def_t md_ipos_def = {11000, INT32_MIN, INT32_MAX, 0, 0, 0,")
    w("                                    MD_PF_NON_VOLATILE | MD_PF_HAS_MIN | MD_PF_HAS_MAX, 0u};")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("params_csv")
    ap.add_argument("extra_csv")
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("-o", "--output")
    g.add_argument("--check", metavar="COMMITTED")
    a = ap.parse_args()
    if a.check:
        for p in (a.params_csv, a.extra_csv):
            if not os.path.exists(p):
                print(f"skipped: {p} not found (the shared spec is not checked out)")
                return 77
    text = render(a.params_csv, a.extra_csv)
    if a.output:
        with open(a.output, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        return 0
    with open(a.check, encoding="utf-8") as f:
        committed = f.read()
    if committed == text:
        print(f"{a.check}: matches the CSVs")
        return 0
    sys.stdout.writelines(difflib.unified_diff(
        committed.splitlines(True), text.splitlines(True), a.check, "generated"))
    print(f"{a.check} differs from the CSVs: re-run {sys.argv[0]} -o {a.check}")
    return 1


if __name__ == "__main__":
    sys.exit(main())
