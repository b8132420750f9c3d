#!/usr/bin/env python3
"""The Wireshark dissector's code tables against the C headers the card is built from.

tools/wireshark/profibus_*.lua name the codes of the wire (delimiters, FDL function and
response codes, SAPs, DP-V1 function numbers and error codes, data set 47 ids, formats and
attributes, the PROFIdrive error numbers the card answers, I&M indices, MOVILINK services
and errors) in Lua tables of its own; the firmware
takes them from fdl_wire.h, dp_wire.h, dpv1_wire.h and movilink_wire.h. Each C macro below is
looked up in its Lua table by the name the dissector shows for it, and the two values must
agree; where a Lua table should hold nothing but header codes, every entry must be claimed by a
macro. The names of the DDLM services are not listed here: they are the labels of the card's
service table (dp_slave/src/dp_services.c), looked up at the SAP dp_service_of() (inline in
dp_services.h) maps to that service, so the dissector, the host tools and the card name a service alike. Exit status 1 and
one line per disagreement otherwise.

Usage: check_wire_constants.py REPO_ROOT
"""
import re
import sys
from pathlib import Path

HEADERS = [
    "dp_slave/include/dp_slave/fdl_wire.h",
    "dp_slave/include/dp_slave/dp_wire.h",
    "dpv1/include/dpv1/dpv1_wire.h",
    "movilink/include/movilink/movilink_wire.h",
]
LUA_GLOB = "tools/wireshark/profibus*.lua"
SERVICES_C = "dp_slave/src/dp_services.c"
SERVICES_H = "dp_slave/include/dp_slave/dp_services.h"


def to_key(value):
    return value


def shift4(value):
    return value >> 4


# (macro, Lua table, name shown for it[, key transform]). A tuple key (a, b) addresses a nested
# table: table[a][b].
CHECKS = [
    # fdl_wire.h
    ("FDL_SD1", "sd_names", "SD1"), ("FDL_SD2", "sd_names", "SD2"),
    ("FDL_SD3", "sd_names", "SD3"), ("FDL_SD4", "sd_names", "SD4"),
    ("FDL_SC", "sd_names", "SC"),
    ("FDL_REQ_TIME_EVENT", "request_functions", "Time event"),
    ("FDL_REQ_SDA_LOW", "request_functions", "SDA low"),
    ("FDL_REQ_SDN_LOW", "request_functions", "SDN low"),
    ("FDL_REQ_SDA_HIGH", "request_functions", "SDA high"),
    ("FDL_REQ_SDN_HIGH", "request_functions", "SDN high"),
    ("FDL_REQ_MSRD", "request_functions", "MSRD"),
    ("FDL_REQ_FDL_STATUS", "request_functions", "FDL status"),
    ("FDL_REQ_SRD_LOW", "request_functions", "SRD low"),
    ("FDL_REQ_SRD_HIGH", "request_functions", "SRD high"),
    ("FDL_REQ_IDENT", "request_functions", "Ident"),
    ("FDL_REQ_LSAP_STATUS", "request_functions", "LSAP status"),
] + [("FDL_RSP_" + n, "response_short", n)
     for n in ("OK", "UE", "RR", "RS", "DL", "NR", "DH", "RDL", "RDH")] + [
    # dp_wire.h
    # (the SAPs of DDLM services and MSAC1: service_checks(), from the service table)
    ("DP_SAP_MSAC2_RM", "sap_services", "MSAC2_RM"),
    ("DP_CFG_DIR_SPECIAL", "cfg_directions", "special format", shift4),
    ("DP_CFG_DIR_IN", "cfg_directions", "input", shift4),
    ("DP_CFG_DIR_OUT", "cfg_directions", "output", shift4),
    ("DP_CFG_DIR_INOUT", "cfg_directions", "input/output", shift4),
    # dpv1_wire.h
    ("DPV1_SAP_C1", "sap_services", "MSAC1"), ("DPV1_SAP_RM", "sap_services", "MSAC2_RM"),
    ("DPV1_FN_IDLE", "dpv1_functions", "Idle"),
    ("DPV1_FN_DATA_TRANSPORT", "dpv1_functions", "Data_Transport"),
    ("DPV1_FN_RM", "dpv1_functions", "Initiate RM"),
    ("DPV1_FN_INITIATE", "dpv1_functions", "Initiate"),
    ("DPV1_FN_ABORT", "dpv1_functions", "Abort"),
    ("DPV1_FN_ALARM_ACK", "dpv1_functions", "Alarm_Ack"),
    ("DPV1_FN_READ", "dpv1_functions", "Read"), ("DPV1_FN_WRITE", "dpv1_functions", "Write"),
    ("DPV1_FN_DATA_TRANSPORT|DPV1_FN_ERROR", "dpv1_functions", "Data_Transport negative"),
    ("DPV1_FN_INITIATE|DPV1_FN_ERROR", "dpv1_functions", "Initiate negative"),
    ("DPV1_FN_ALARM_ACK|DPV1_FN_ERROR", "dpv1_functions", "Alarm_Ack negative"),
    ("DPV1_FN_READ|DPV1_FN_ERROR", "dpv1_functions", "Read negative"),
    ("DPV1_FN_WRITE|DPV1_FN_ERROR", "dpv1_functions", "Write negative"),
    ("DPV1_ERROR_DECODE", "dpv1_error_decodes", "DPV1"),
    ("DPV1_ERR_INVALID_INDEX", "dpv1_error_classes", "access", shift4),
    ("DPV1_ERR_NOT_SUPPORTED", "dpv1_error_classes", "application", shift4),
] + [(m, "dpv1_error_codes", n, lambda v: (v >> 4, v & 0xF)) for m, n in (
    ("DPV1_ERR_INVALID_INDEX", "invalid index"), ("DPV1_ERR_WRITE_LENGTH", "write length error"),
    ("DPV1_ERR_STATE_CONFLICT", "state conflict"), ("DPV1_ERR_ACCESS_DENIED", "access denied"),
    ("DPV1_ERR_INVALID_RANGE", "invalid range"),
    ("DPV1_ERR_NOT_SUPPORTED", "feature not supported"))] + [
    ("DPV1_ABORT_INSTANCE_C2", "abort_instances", "MSAC_C2", shift4),
    ("DPV1_ABORT_REASON_FE", "abort_reasons", "FE bad request PDU"),
    ("DPV1_ABORT_REASON_TIMEOUT", "abort_reasons", "TO connection timeout"),
    ("DPV1_ABORT_REASON_RESOURCE", "abort_reasons", "RES resource"),
    ("DS47_ID_REQUEST", "ds47_ids", "request parameter"),
    ("DS47_ID_CHANGE", "ds47_ids", "change parameter"),
    ("DS47_ID_MOVILINK", "ds47_ids", "MOVILINK service"),
    ("DS47_ID_REQUEST|DS47_ID_ERROR", "ds47_ids", "request parameter, negative"),
    ("DS47_ID_CHANGE|DS47_ID_ERROR", "ds47_ids", "change parameter, negative"),
    ("DS47_ID_MOVILINK|DS47_ID_ERROR", "ds47_ids", "MOVILINK service, negative"),
    ("DS47_ATTR_VALUE", "profidrive_attributes", "value"),
    ("DS47_ATTR_ML_READ", "movilink_attributes", "read"),
    ("DS47_ATTR_ML_WRITE", "movilink_attributes", "write"),
    ("DS47_ATTR_ML_WRITE_VOLATILE", "movilink_attributes", "write volatile"),
    ("DS47_FORMAT_ZERO", "ds47_formats", "Zero"),
    ("DS47_FORMAT_DWORD", "ds47_formats", "Double word"),
    ("DS47_FORMAT_ERROR", "ds47_formats", "Error"),
    ("IM_INDEX_0", "im_records", "I&M0"), ("IM_INDEX_LAST", "im_records", "I&M4"),
] + [("PD_ERR_" + m, "profidrive_errors", n) for m, n in (
    ("PARAMETER_NUMBER", "impermissible parameter number"),
    ("READ_ONLY", "parameter value cannot be changed"),
    ("LIMIT_EXCEEDED", "low or high limit exceeded"), ("SUBINDEX", "faulty subindex"),
    ("NO_ARRAY", "no array"), ("DATA_TYPE", "incorrect data type"),
    ("OPERATING_STATE", "request cannot be executed because of operating state"),
    ("VALUE_IMPERMISSIBLE", "value impermissible"), ("FORMAT", "illegal format"),
    ("VALUE_COUNT", "number of values inconsistent"), ("AXIS_NONEXISTENT", "axis nonexistent"))] + [
    # movilink_wire.h
    ("ML_SVC_NONE", "ml_services", "no service"), ("ML_SVC_READ", "ml_services", "read"),
    ("ML_SVC_WRITE", "ml_services", "write"),
    ("ML_SVC_WRITE_VOLATILE", "ml_services", "write volatile"),
    ("ML_SVC_READ_MIN", "ml_services", "read minimum"),
    ("ML_SVC_READ_MAX", "ml_services", "read maximum"),
    ("ML_SVC_READ_DEFAULT", "ml_services", "read default"),
    ("ML_SVC_READ_SCALE", "ml_services", "read scale"),
    ("ML_SVC_READ_ATTRIBUTE", "ml_services", "read attribute"),
    ("ML_CLASS_SERVICE", "ml_error_classes", "service"),
    ("ML_CLASS_ACCESS", "ml_error_classes", "access"),
    ("ML_CLASS_OTHER", "ml_error_classes", "other"),
] + [("ML_ADD_" + m, "ml_class8_codes", n) for m, n in (
    ("ILLEGAL_INDEX", "illegal parameter index"),
    ("NOT_IMPLEMENTED", "function/parameter not implemented"),
    ("READ_ONLY", "read access only"), ("PARAMETER_LOCK", "parameter lock active"),
    ("FACTORY_SETTING_ACTIVE", "factory setting active"), ("TOO_HIGH", "value too high"),
    ("TOO_LOW", "value too low"),
    ("OPTION_MISSING", "option card required for this function missing"),
    ("SYSTEM_ERROR", "system software error"),
    ("ACCESS_PROTECTED", "parameter is access-protected"),
    ("CONTROLLER_INHIBIT_REQUIRED", "controller inhibit required"),
    ("VALUE_NOT_PERMITTED", "value not permitted"),
    ("FACTORY_SETTING_ACTIVATED", "factory setting was activated"),
    ("NOT_SAVED", "parameter not saved in EEPROM"),
    ("OUTPUT_STAGE_ENABLED", "parameter cannot be changed with output stage enabled"))]

# MOVILINK errors the dissector spells out as 16-bit values (class << 8 | code) in
# movilink_error_text(): (class macro, code macro, the text's start).
ML_ERROR_VALUES = [
    ("ML_CLASS_SERVICE", "ML_CODE_ILLEGAL_PARAMETER", "class 5 code 5"),
    ("ML_CLASS_ACCESS", "ML_CODE_HARDWARE_FAULT", "class 6 code 2"),
    ("ML_CLASS_ACCESS", "ML_CODE_TYPE_CONFLICT", "class 6 code 8"),
]

# Tables that hold header codes only, apart from the keys listed (codes the firmware does not
# use: TE/CE requests, alarm SAP 50, Set_Ext_Prm 53, MM services 54).
COMPLETE = {
    "sd_names": set(), "request_functions": {0xA, 0xB}, "response_short": set(),
    "sap_services": {50, 53, 54}, "dpv1_functions": set(), "ml_services": set(),
    "ds47_formats": set(range(0x01, 0x0B)) | {0x41, 0x42},
}


def c_defines(root):
    raw = {}
    for rel in HEADERS:
        text = re.sub(r"/\*.*?\*/", "", (root / rel).read_text(), flags=re.S)
        for name, expr in re.findall(r"^\s*#define\s+(\w+)[ \t]+(.+?)\s*$", text, flags=re.M):
            raw[name] = expr
    values = {}

    def evaluate(name, depth=0):
        if name in values:
            return values[name]
        if depth > 20 or name not in raw:
            return None
        expr = re.sub(r"\b(0[xX][0-9A-Fa-f]+|\d+)[uU]?\b", r"\1", raw[name])
        for ref in set(re.findall(r"\b[A-Z_][A-Z0-9_]*\b", expr)):
            v = evaluate(ref, depth + 1)
            if v is None:
                return None
            expr = re.sub(r"\b%s\b" % ref, str(v), expr)
        if not re.fullmatch(r"[0-9a-fA-FxX()+\-*|&<> ]+", expr):
            return None
        values[name] = int(eval(expr))  # digits and operators only, checked above
        return values[name]

    for name in raw:
        evaluate(name)
    return values


def c_source(root, rel):
    return re.sub(r"/\*.*?\*/", "", (root / rel).read_text(), flags=re.S)


def service_table(root, problems):
    """The rows of dp_services.c, {enumerator: (name, label)}, and the SAP cases of
    dp_service_of(), [(DP_SAP_ macro, enumerator)]."""
    text = c_source(root, SERVICES_C)
    # A label may be a string macro of dp_services.h (one a host tool composes names from).
    literals = dict(re.findall(r'^\s*#define\s+(\w+)\s+"([^"]*)"\s*$',
                               c_source(root, SERVICES_H), flags=re.M))
    rows = {}
    for svc, name, label, macro in re.findall(
            r'\[\s*(\w+)\s*\]\s*=\s*\{\s*"([^"]*)"\s*,\s*(?:"([^"]*)"|(\w+))', text):
        if macro and macro not in literals:
            problems.append("%s %s: label %s is not a string macro of %s" % (
                SERVICES_C, svc, macro, SERVICES_H))
        rows[svc] = (name, literals.get(macro, "") if macro else label)
    # dp_service_of() is inline in the header: it is on the slave's reply path.
    body = re.search(r"dp_service_of\s*\([^)]*\)\s*\{(.*?)\n\}", c_source(root, SERVICES_H),
                     flags=re.S)
    cases = re.findall(r"case\s+(DP_SAP_\w+)\s*:\s*return\s+(\w+)\s*;",
                       body.group(1) if body else "")
    if not rows or not cases:
        problems.append("%s: no service rows {name, label, ...} or no dp_service_of() cases "
                        "found" % SERVICES_C)
    for svc, (name, label) in sorted(rows.items()):
        # Only the spelling may differ ("DDLM_RD_Inp" / "Rd_Inp"), never the service.
        if name.startswith("DDLM_") and label.lower() != name[len("DDLM_"):].lower():
            problems.append('%s %s: label "%s" is not the name "%s" without DDLM_' % (
                SERVICES_C, svc, label, name))
    for svc in sorted(set(rows) - {s for _, s in cases}):
        if svc.startswith("DDLM_") and svc != "DDLM_DATA_EXCHANGE":
            problems.append("%s: %s has no SAP case in dp_service_of()" % (SERVICES_C, svc))
    for macro, svc in cases:
        if svc not in rows:
            problems.append("%s: dp_service_of() returns %s for %s, which has no row" % (
                SERVICES_C, svc, macro))
    return rows, cases


def service_checks(rows, cases):
    """CHECKS entries for the SAP of every service dp_service_of() maps one SAP to."""
    return [(macro, "sap_services", rows[svc][1]) for macro, svc in cases if svc in rows]


def check_sapless_services(rows, lua, problems):
    # service_of_sap() calls the connection SAPs below the resource manager MSAC2, and
    # telegrams without SAPs carry Data_Exchange: neither has a sap_services entry.
    m = re.search(r'if\s+sap\s*<=\s*\d+\s+then\s+return\s+"([^"]*)"', lua)
    want = rows.get("MSAC2S", (None, None))[1]
    if m is None or m.group(1) != want:
        problems.append('service_of_sap(): the MSAC2 connection SAPs are named %s, the table\'s '
                        'label of MSAC2S is "%s"' % (repr(m.group(1)) if m else "nowhere", want))
    want = rows.get("DDLM_DATA_EXCHANGE", (None, None))[1]
    if want not in re.findall(r'\bservice\s*=\s*"([^"]*)"', lua):
        problems.append('no telegram without SAP gets service = "%s" (the table\'s label of '
                        'DDLM_DATA_EXCHANGE)' % want)


def lua_source(root):
    files = sorted(root.glob(LUA_GLOB))
    if not files:
        sys.exit("check_wire_constants: no %s under %s" % (LUA_GLOB, root))
    text = "\n".join(f.read_text() for f in files)
    return re.sub(r"--[^\n]*", "", text)


def table_body(lua, name):
    m = re.search(r"\blocal\s+%s\s*=\s*\{" % re.escape(name), lua)
    if m is None:
        return None
    depth, i = 1, m.end()
    while depth > 0 and i < len(lua):
        depth += {"{": 1, "}": -1}.get(lua[i], 0)
        i += 1
    return lua[m.end():i - 1]


ENTRY = r"\[\s*(0[xX][0-9A-Fa-f]+|\d+)\s*\]\s*=\s*"


def lua_table(lua, name):
    body = table_body(lua, name)
    if body is None:
        return None
    table = {}
    for key, inner in re.findall(ENTRY + r"\{(.*?)\}", body, flags=re.S):
        for k2, text in re.findall(ENTRY + r'"((?:[^"\\]|\\.)*)"', inner):
            table[(int(key, 0), int(k2, 0))] = text
    flat = re.sub(ENTRY + r"\{.*?\}", "", body, flags=re.S)
    for key, text in re.findall(ENTRY + r'"((?:[^"\\]|\\.)*)"', flat):
        table[int(key, 0)] = text
    return table


def fmt(key):
    if isinstance(key, tuple):
        return "[0x%X][%d]" % key
    return "0x%02X" % key


def macro_value(defs, spec):
    value = 0
    for part in spec.split("|"):
        if part not in defs:
            return None
        value |= defs[part]
    return value


def check_names(defs, lua, checks, problems):
    claimed = {}
    tables = {}
    for entry in checks:
        macro, tname, text = entry[:3]
        transform = entry[3] if len(entry) > 3 else to_key
        value = macro_value(defs, macro)
        if value is None:
            problems.append("%s: not a numeric #define in %s" % (macro, ", ".join(HEADERS)))
            continue
        if tname not in tables:
            tables[tname] = lua_table(lua, tname)
        table = tables[tname]
        if table is None:
            problems.append("Lua table %s not found in %s" % (tname, LUA_GLOB))
            continue
        key = transform(value)
        claimed.setdefault(tname, set()).add(key)
        have = [k for k, t in table.items() if t == text]
        if table.get(key) != text:
            where = ("at %s" % ", ".join(fmt(k) for k in have)) if have else "nowhere"
            problems.append('%s = %s in the header, but Lua %s%s is %s and "%s" is %s' % (
                macro, fmt(value), tname, "[" + fmt(key) + "]", repr(table.get(key)), text,
                where))
    for tname, extra in COMPLETE.items():
        table = tables.get(tname) or lua_table(lua, tname) or {}
        for key in sorted(set(table) - claimed.get(tname, set()) - extra, key=str):
            problems.append('Lua %s[%s] = "%s" matches no #define of the headers' % (
                tname, fmt(key), table[key]))


def check_ml_error_values(defs, lua, problems):
    for class_macro, code_macro, text in ML_ERROR_VALUES:
        value = (defs.get(class_macro, -1) << 8) | defs.get(code_macro, -1)
        m = re.search(r'v\s*==\s*(0x[0-9A-Fa-f]+)\s*then\s+return\s+"%s' % re.escape(text), lua)
        if m is None:
            problems.append('movilink_error_text(): no "%s" case' % text)
        elif int(m.group(1), 16) != value:
            problems.append('movilink_error_text(): "%s" at %s, but %s << 8 | %s = 0x%04X' % (
                text, m.group(1), class_macro, code_macro, value))


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    defs = c_defines(root)
    lua = lua_source(root)
    problems = []
    rows, cases = service_table(root, problems)
    checks = CHECKS + service_checks(rows, cases)
    check_names(defs, lua, checks, problems)
    check_sapless_services(rows, lua, problems)
    check_ml_error_values(defs, lua, problems)
    for p in problems:
        print("MISMATCH: " + p)
    n = len(checks) + 2 + len(ML_ERROR_VALUES)
    if problems:
        print("%d of the dissector's codes disagree with the C headers and the service table"
              % len(problems))
        return 1
    print("%d codes of the dissector agree with the C headers and the service table" % n)
    return 0


if __name__ == "__main__":
    sys.exit(main())
