-- PROFIBUS FDL / DP-V0 / DP-V1 dissector for Wireshark and tshark (Lua; tested with 4.0).
--
-- Wireshark has no PROFIBUS dissector and wiretap does not map LINKTYPE_PROFIBUS_DL (257), so
-- this registers for LINKTYPE_USER0 (147): each record is one telegram, raw octets from the
-- start delimiter to the end delimiter (SC: one octet, SD4: three), no pseudo-header.
-- Usage: tools/wireshark/README.md. Layouts: the protocol notes protocol.md §A1, §A3, §A4, §A5,
-- protocol.md §B6, §B7 and docs/dpv1.md.
--
-- A telegram that is too short, inconsistent or carries an unknown code gets an expert info
-- ("malformed") and decoding stops there; no record may raise a Lua error.

local proto = Proto("profibus", "PROFIBUS (FDL, DP, DP-V1)")

-- Bit helpers in plain arithmetic: Lua 5.2 (Wireshark 4.0) has bit32, Lua 5.3/5.4 (newer
-- Wireshark builds) have operators instead, and neither works in both.
local function bits(v, lo, width) return math.floor(v / 2 ^ lo) % math.floor(2 ^ width) end
local function has(v, mask) return math.floor(v / mask) % 2 == 1 end

------------------------------------------------------------------------------------------------
-- Value names

local sd_names = { [0x10] = "SD1", [0x68] = "SD2", [0xA2] = "SD3", [0xDC] = "SD4", [0xE5] = "SC" }
local request_functions = {
    [0x0] = "Time event", [0x3] = "SDA low", [0x4] = "SDN low", [0x5] = "SDA high",
    [0x6] = "SDN high", [0x7] = "MSRD", [0x9] = "FDL status", [0xA] = "Time event (TE)",
    [0xB] = "Counter event (CE)", [0xC] = "SRD low", [0xD] = "SRD high", [0xE] = "Ident",
    [0xF] = "LSAP status",
}
local response_codes = {
    [0x0] = "OK", [0x1] = "UE (user error)", [0x2] = "RR (no resource)",
    [0x3] = "RS (no service / SAP not activated)", [0x8] = "DL (data low)",
    [0x9] = "NR (no response data)", [0xA] = "DH (data high: diagnosis pending)",
    [0xC] = "RDL (data low, no resource)", [0xD] = "RDH (data high, no resource)",
}
local response_short = {
    [0x0] = "OK", [0x1] = "UE", [0x2] = "RR", [0x3] = "RS", [0x8] = "DL", [0x9] = "NR",
    [0xA] = "DH", [0xC] = "RDL", [0xD] = "RDH",
}
local station_types = {
    [0] = "slave", [1] = "master not ready", [2] = "master ready, without token",
    [3] = "master in token ring",
}

local sap_services = {
    [49] = "MSAC2_RM", [50] = "MSAC1_Alarm", [51] = "MSAC1", [53] = "Set_Ext_Prm",
    [54] = "MM_Service", [55] = "Set_Slave_Add", [56] = "Rd_Inp", [57] = "Rd_Outp",
    [58] = "Global_Control", [59] = "Get_Cfg", [60] = "Slave_Diag", [61] = "Set_Prm",
    [62] = "Chk_Cfg",
}
local function service_of_sap(sap)
    if sap == nil then return nil end
    if sap <= 48 then return "MSAC2" end
    return sap_services[sap] or string.format("SAP %d", sap)
end

local cfg_directions = { [0] = "special format", [1] = "input", [2] = "output", [3] = "input/output" }
local cfg_special = {
    [0] = "free place", [1] = "input length octet follows", [2] = "output length octet follows",
    [3] = "output and input length octets follow",
}
local alarm_modes = {
    [0] = "1 of each type", [1] = "2 in total", [2] = "4 in total", [3] = "8 in total",
    [4] = "12 in total", [5] = "16 in total", [6] = "24 in total", [7] = "32 in total",
}
local ext_diag_types = {
    [0] = "device-related", [1] = "identifier-related", [2] = "channel-related",
    [3] = "reserved",
}

local ml_services = {
    [0] = "no service", [1] = "read", [2] = "write", [3] = "write volatile", [4] = "read minimum",
    [5] = "read maximum", [6] = "read default", [7] = "read scale", [8] = "read attribute",
}
-- MOVILINK index -> "P100 setpoint source": movidrive_params.lua beside this script, generated
-- from the emulated MOVIDRIVE's parameter data (sim_host/movidrive/tools/gen_params.py). Without
-- it (e.g. this file alone in the plugin folder) indices stay bare numbers.
local ml_param_names = {}
do
    local dir = ""
    if debug and debug.getinfo then
        local src = (debug.getinfo(1, "S") or {}).source or ""
        dir = src:match("^@(.*[/\\])") or ""
    end
    local ok, t = pcall(dofile, dir .. "movidrive_params.lua")
    if ok and type(t) == "table" then ml_param_names = t end
end
-- "8461 (P100 setpoint source)", or "8461" for an index the table does not name.
local function ml_index_text(index)
    local name = ml_param_names[index]
    return name and string.format("%d (%s)", index, name) or tostring(index)
end

local ml_lengths = { [0] = "1 octet", [1] = "2 octets", [2] = "3 octets", [3] = "4 octets" }
local ml_error_classes = {
    [1] = "vfd state", [2] = "application reference", [3] = "definition", [4] = "resource",
    [5] = "service", [6] = "access", [7] = "ov", [8] = "other",
}
-- Class 8 additional codes (protocol.md §B6).
local ml_class8_codes = {
    [0x10] = "illegal parameter index", [0x11] = "function/parameter not implemented",
    [0x12] = "read access only", [0x13] = "parameter lock active",
    [0x14] = "factory setting active", [0x15] = "value too high", [0x16] = "value too low",
    [0x17] = "option card required for this function missing",
    [0x18] = "system software error", [0x19] = "access only via RS-485 process interface X13",
    [0x1A] = "access only via RS-485 diagnostic interface", [0x1B] = "parameter is access-protected",
    [0x1C] = "controller inhibit required", [0x1D] = "value not permitted",
    [0x1E] = "factory setting was activated", [0x1F] = "parameter not saved in EEPROM",
    [0x20] = "parameter cannot be changed with output stage enabled",
    [0x23] = "only with IPOS program stopped", [0x24] = "only with auto-setup off",
}
-- MOVILINK errors as 16-bit values in data set 47 (class << 8 | code).
local function movilink_error_text(v)
    local class, code = bits(v, 8, 8), bits(v, 0, 8)
    if class == 8 then
        return string.format("class 8, additional code 0x%02X: %s", code,
            ml_class8_codes[code] or "unknown")
    elseif v == 0x0505 then return "class 5 code 5: wrong management/reserved coding"
    elseif v == 0x0602 then return "class 6 code 2: card <-> inverter communication fault"
    elseif v == 0x0502 then return "class 5 code 2: connection timeout"
    elseif v == 0x0608 then return "class 6 code 8: type conflict (data length)"
    end
    return string.format("class %d (%s), code %d", class, ml_error_classes[class] or "unknown", code)
end

local dpv1_functions = {
    [0x48] = "Idle", [0x51] = "Data_Transport", [0x56] = "Initiate RM", [0x57] = "Initiate",
    [0x58] = "Abort", [0x5C] = "Alarm_Ack", [0x5E] = "Read", [0x5F] = "Write",
    [0xD1] = "Data_Transport negative", [0xD7] = "Initiate negative", [0xDC] = "Alarm_Ack negative",
    [0xDE] = "Read negative", [0xDF] = "Write negative",
}
local dpv1_error_decodes = { [0x80] = "DPV1", [0xFE] = "FMS", [0xFF] = "HART" }
local dpv1_error_classes = {
    [0xA] = "application", [0xB] = "access", [0xC] = "resource", [0xD] = "user specific",
    [0xE] = "user specific", [0xF] = "user specific",
}
local dpv1_error_codes = {
    [0xA] = { [0] = "read error", [1] = "write error", [2] = "module failure",
              [8] = "version conflict", [9] = "feature not supported" },
    [0xB] = { [0] = "invalid index", [1] = "write length error", [2] = "invalid slot",
              [3] = "type conflict", [4] = "invalid area", [5] = "state conflict",
              [6] = "access denied", [7] = "invalid range", [8] = "invalid parameter",
              [9] = "invalid type" },
    [0xC] = { [0] = "read constraint conflict", [1] = "write constraint conflict",
              [2] = "resource busy", [3] = "resource unavailable" },
}
local function dpv1_error_text(e1)
    local class, code = bits(e1, 4, 4), bits(e1, 0, 4)
    local codes = dpv1_error_codes[class]
    return string.format("%s, %s", dpv1_error_classes[class] or "reserved class",
        codes and codes[code] or string.format("code %d", code))
end
local abort_subnets = { [0] = "none", [1] = "local", [2] = "remote" }
local abort_instances = { [0] = "FDL", [1] = "MSAC_C2", [2] = "user" }
local abort_reasons = {
    [1] = "SE sequence error", [2] = "FE bad request PDU", [3] = "TO connection timeout",
    [4] = "RE bad response PDU", [5] = "IV invalid service from user",
    [6] = "STO Send_Timeout too small", [7] = "IA invalid additional address info",
    [8] = "OC waiting for FDL_DATA_REPLY.con", [15] = "RES resource",
}

local ds47_ids = {
    [0x01] = "request parameter", [0x02] = "change parameter", [0x40] = "MOVILINK service",
    [0x41] = "MOVILINK (reserved 0x41)", [0x81] = "request parameter, negative",
    [0x82] = "change parameter, negative", [0xC0] = "MOVILINK service, negative",
}
local ds47_formats = {
    [0x01] = "Boolean", [0x02] = "Integer8", [0x03] = "Integer16", [0x04] = "Integer32",
    [0x05] = "Unsigned8", [0x06] = "Unsigned16", [0x07] = "Unsigned32", [0x08] = "FloatingPoint",
    [0x09] = "VisibleString", [0x0A] = "OctetString", [0x40] = "Zero", [0x41] = "Byte",
    [0x42] = "Word", [0x43] = "Double word", [0x44] = "Error",
}
local ds47_format_sizes = {
    [0x01] = 1, [0x02] = 1, [0x03] = 2, [0x04] = 4, [0x05] = 1, [0x06] = 2, [0x07] = 4,
    [0x08] = 4, [0x09] = 1, [0x0A] = 1, [0x40] = 0, [0x41] = 1, [0x42] = 2, [0x43] = 4,
    [0x44] = 2,
}
local profidrive_attributes = { [0x10] = "value", [0x20] = "description", [0x30] = "text" }
local movilink_attributes = {
    [0x00] = "no service", [0x10] = "read", [0x20] = "write", [0x30] = "write volatile",
}
local profidrive_errors = {
    [0x00] = "impermissible parameter number", [0x01] = "parameter value cannot be changed",
    [0x02] = "low or high limit exceeded", [0x03] = "faulty subindex", [0x04] = "no array",
    [0x05] = "incorrect data type", [0x06] = "setting not permitted (may only be reset)",
    [0x07] = "description element cannot be changed", [0x09] = "no description data available",
    [0x0B] = "no operation priority", [0x0F] = "no text array available",
    [0x11] = "request cannot be executed because of operating state",
    [0x14] = "value impermissible", [0x15] = "response too long",
    [0x16] = "parameter address impermissible", [0x17] = "illegal format",
    [0x18] = "number of values inconsistent", [0x19] = "axis nonexistent",
}
local function profidrive_error_text(v)
    if profidrive_errors[v] then return profidrive_errors[v] end
    if v >= 0x65 and v <= 0xFF then return "manufacturer specific" end
    return "unknown"
end
local im_records = {
    [0xFDE8] = "I&M0", [0xFDE9] = "I&M1", [0xFDEA] = "I&M2", [0xFDEB] = "I&M3", [0xFDEC] = "I&M4",
}

------------------------------------------------------------------------------------------------
-- Fields

local F = {
    sd = ProtoField.uint8("profibus.sd", "Start delimiter", base.HEX, sd_names),
    le = ProtoField.uint8("profibus.le", "LE", base.DEC),
    ler = ProtoField.uint8("profibus.ler", "LEr", base.DEC),
    sd_repeat = ProtoField.uint8("profibus.sd_repeat", "Start delimiter (repeated)", base.HEX),
    da = ProtoField.uint8("profibus.da", "DA", base.DEC, nil, 0x7F),
    da_ext = ProtoField.bool("profibus.da.ext", "DA extension (DAE present)", 8, nil, 0x80),
    sa = ProtoField.uint8("profibus.sa", "SA", base.DEC, nil, 0x7F),
    sa_ext = ProtoField.bool("profibus.sa.ext", "SA extension (SAE present)", 8, nil, 0x80),
    fc = ProtoField.uint8("profibus.fc", "FC", base.HEX),
    fc_reserved = ProtoField.bool("profibus.fc.reserved", "Reserved", 8, nil, 0x80),
    fc_request = ProtoField.bool("profibus.fc.request", "Request", 8,
        { "request", "response" }, 0x40),
    fc_fcb = ProtoField.bool("profibus.fc.fcb", "FCB (frame count bit)", 8, nil, 0x20),
    fc_fcv = ProtoField.bool("profibus.fc.fcv", "FCV (frame count bit valid)", 8, nil, 0x10),
    fc_function = ProtoField.uint8("profibus.fc.function", "Function", base.HEX,
        request_functions, 0x0F),
    fc_station_type = ProtoField.uint8("profibus.fc.station_type", "Station type", base.DEC,
        station_types, 0x30),
    fc_response = ProtoField.uint8("profibus.fc.response", "Response", base.HEX,
        response_codes, 0x0F),
    fc_repeat = ProtoField.bool("profibus.fc.repeat", "Repetition (FCB unchanged)"),
    dae = ProtoField.uint8("profibus.dae", "DAE", base.HEX),
    sae = ProtoField.uint8("profibus.sae", "SAE", base.HEX),
    ae_more = ProtoField.bool("profibus.ae.more", "Another extension octet follows", 8, nil, 0x80),
    ae_segment = ProtoField.bool("profibus.ae.segment", "Segment address", 8,
        { "segment address", "SAP" }, 0x40),
    dsap = ProtoField.uint8("profibus.dsap", "DSAP", base.DEC, nil, 0x3F),
    ssap = ProtoField.uint8("profibus.ssap", "SSAP", base.DEC, nil, 0x3F),
    segment = ProtoField.uint8("profibus.segment", "Segment", base.DEC, nil, 0x3F),
    service = ProtoField.string("profibus.service", "Service"),
    du = ProtoField.bytes("profibus.du", "Data unit"),
    du_len = ProtoField.uint8("profibus.du_len", "Data length after the SAP octets", base.DEC),
    fcs = ProtoField.uint8("profibus.fcs", "FCS", base.HEX),
    fcs_ok = ProtoField.bool("profibus.fcs_ok", "FCS correct"),
    fcs_computed = ProtoField.uint8("profibus.fcs.computed", "FCS computed", base.HEX),
    ed = ProtoField.uint8("profibus.ed", "End delimiter", base.HEX),
    trailing = ProtoField.bytes("profibus.trailing", "Octets after the telegram"),
    response_in = ProtoField.framenum("profibus.response_in", "Response in", base.NONE,
        frametype.RESPONSE),
    response_to = ProtoField.framenum("profibus.response_to", "Response to", base.NONE,
        frametype.REQUEST),

    -- DP-V0
    ident = ProtoField.uint16("profibus.dp.ident", "Ident number", base.HEX),
    prm_status = ProtoField.uint8("profibus.dp.prm.station_status", "Station_Status", base.HEX),
    prm_lock = ProtoField.bool("profibus.dp.prm.lock_req", "Lock_Req", 8, nil, 0x80),
    prm_unlock = ProtoField.bool("profibus.dp.prm.unlock_req", "Unlock_Req", 8, nil, 0x40),
    prm_sync = ProtoField.bool("profibus.dp.prm.sync_req", "Sync_Req", 8, nil, 0x20),
    prm_freeze = ProtoField.bool("profibus.dp.prm.freeze_req", "Freeze_Req", 8, nil, 0x10),
    prm_wd_on = ProtoField.bool("profibus.dp.prm.wd_on", "WD_On", 8, nil, 0x08),
    prm_status_res = ProtoField.uint8("profibus.dp.prm.reserved", "Reserved", base.HEX, nil, 0x07),
    prm_wd1 = ProtoField.uint8("profibus.dp.prm.wd_fact_1", "WD_Fact_1", base.DEC),
    prm_wd2 = ProtoField.uint8("profibus.dp.prm.wd_fact_2", "WD_Fact_2", base.DEC),
    prm_wd_ms = ProtoField.uint32("profibus.dp.prm.watchdog_ms", "Watchdog time (ms)", base.DEC),
    prm_tsdr = ProtoField.uint8("profibus.dp.prm.min_tsdr", "min TSDR (bit times, 0 = unchanged)",
        base.DEC),
    prm_group = ProtoField.uint8("profibus.dp.prm.group_ident", "Group_Ident", base.HEX),
    prm_dpv1_1 = ProtoField.uint8("profibus.dp.prm.dpv1_status_1", "DPV1_Status_1", base.HEX),
    prm_dpv1_enable = ProtoField.bool("profibus.dp.prm.dpv1_enable", "DPV1_Enable", 8, nil, 0x80),
    prm_fail_safe = ProtoField.bool("profibus.dp.prm.fail_safe", "Fail_Safe", 8, nil, 0x40),
    prm_publisher = ProtoField.bool("profibus.dp.prm.publisher_enable", "Publisher_Enable", 8,
        nil, 0x20),
    prm_wd_base = ProtoField.bool("profibus.dp.prm.wd_base_1ms", "WD_Base_1ms", 8, nil, 0x04),
    prm_dis_stop = ProtoField.bool("profibus.dp.prm.dis_stop_control", "Dis_Stop_Control", 8,
        nil, 0x02),
    prm_dis_start = ProtoField.bool("profibus.dp.prm.dis_start_control", "Dis_Start_Control", 8,
        nil, 0x01),
    prm_dpv1_2 = ProtoField.uint8("profibus.dp.prm.dpv1_status_2", "DPV1_Status_2", base.HEX),
    prm_al_pull = ProtoField.bool("profibus.dp.prm.pull_plug_alarm", "Pull/Plug alarm", 8, nil, 0x80),
    prm_al_process = ProtoField.bool("profibus.dp.prm.process_alarm", "Process alarm", 8, nil, 0x40),
    prm_al_diag = ProtoField.bool("profibus.dp.prm.diagnostic_alarm", "Diagnostic alarm", 8, nil,
        0x20),
    prm_al_manuf = ProtoField.bool("profibus.dp.prm.manufacturer_alarm",
        "Manufacturer-specific alarm", 8, nil, 0x10),
    prm_al_status = ProtoField.bool("profibus.dp.prm.status_alarm", "Status alarm", 8, nil, 0x08),
    prm_al_update = ProtoField.bool("profibus.dp.prm.update_alarm", "Update alarm", 8, nil, 0x04),
    prm_chk_cfg_mode = ProtoField.bool("profibus.dp.prm.check_cfg_mode", "Check_Cfg_Mode", 8, nil,
        0x01),
    prm_dpv1_3 = ProtoField.uint8("profibus.dp.prm.dpv1_status_3", "DPV1_Status_3", base.HEX),
    prm_prmcmd = ProtoField.bool("profibus.dp.prm.prm_cmd", "PrmCmd", 8, nil, 0x80),
    prm_isom = ProtoField.bool("profibus.dp.prm.isom_req", "IsoM_Req", 8, nil, 0x10),
    prm_structure = ProtoField.bool("profibus.dp.prm.prm_structure", "Prm_Structure", 8, nil, 0x08),
    prm_alarm_mode = ProtoField.uint8("profibus.dp.prm.alarm_mode", "Alarm_Mode", base.DEC,
        alarm_modes, 0x07),
    prm_user = ProtoField.bytes("profibus.dp.prm.user_prm", "User_Prm_Data"),
    prm_dfp21b_alarm = ProtoField.bool("profibus.dp.prm.dfp21b_diag_alarm",
        "DFP21B diagnostic alarm on inverter fault", base.NONE, { "on (00)", "off (01)" }),

    cfg_id = ProtoField.uint8("profibus.dp.cfg.id", "Identifier", base.HEX),
    cfg_consistency = ProtoField.bool("profibus.dp.cfg.consistency", "Consistency", 8,
        { "whole length", "byte/word" }, 0x80),
    cfg_words = ProtoField.bool("profibus.dp.cfg.words", "Unit", 8, { "words", "bytes" }, 0x40),
    cfg_direction = ProtoField.uint8("profibus.dp.cfg.direction", "Direction", base.DEC,
        cfg_directions, 0x30),
    cfg_length = ProtoField.uint8("profibus.dp.cfg.length_code", "Length - 1", base.DEC, nil, 0x0F),
    cfg_special = ProtoField.uint8("profibus.dp.cfg.special", "Special format", base.DEC,
        cfg_special, 0xC0),
    cfg_manuf_len = ProtoField.uint8("profibus.dp.cfg.manufacturer_length",
        "Manufacturer-specific octets", base.DEC, nil, 0x0F),
    cfg_len_octet = ProtoField.uint8("profibus.dp.cfg.length_octet", "Length octet", base.HEX),
    cfg_len_consistency = ProtoField.bool("profibus.dp.cfg.length_consistency", "Consistency", 8,
        { "whole length", "byte/word" }, 0x80),
    cfg_len_words = ProtoField.bool("profibus.dp.cfg.length_words", "Unit", 8,
        { "words", "bytes" }, 0x40),
    cfg_len_code = ProtoField.uint8("profibus.dp.cfg.length_code6", "Length - 1", base.DEC, nil,
        0x3F),
    cfg_manuf = ProtoField.bytes("profibus.dp.cfg.manufacturer_data", "Manufacturer-specific data"),
    cfg_in = ProtoField.uint16("profibus.dp.cfg.in_octets", "Input octets", base.DEC),
    cfg_out = ProtoField.uint16("profibus.dp.cfg.out_octets", "Output octets", base.DEC),
    cfg_total_in = ProtoField.uint16("profibus.dp.cfg.total_in", "Total input octets", base.DEC),
    cfg_total_out = ProtoField.uint16("profibus.dp.cfg.total_out", "Total output octets", base.DEC),

    diag_s1 = ProtoField.uint8("profibus.dp.diag.status_1", "Station_Status_1", base.HEX),
    diag_non_existent = ProtoField.bool("profibus.dp.diag.station_non_existent",
        "Station_Non_Existent", 8, nil, 0x01),
    diag_not_ready = ProtoField.bool("profibus.dp.diag.station_not_ready", "Station_Not_Ready", 8,
        nil, 0x02),
    diag_cfg_fault = ProtoField.bool("profibus.dp.diag.cfg_fault", "Cfg_Fault", 8, nil, 0x04),
    diag_ext_diag = ProtoField.bool("profibus.dp.diag.ext_diag", "Ext_Diag", 8, nil, 0x08),
    diag_not_supported = ProtoField.bool("profibus.dp.diag.not_supported", "Not_Supported", 8, nil,
        0x10),
    diag_invalid_resp = ProtoField.bool("profibus.dp.diag.invalid_slave_response",
        "Invalid_Slave_Response", 8, nil, 0x20),
    diag_prm_fault = ProtoField.bool("profibus.dp.diag.prm_fault", "Prm_Fault", 8, nil, 0x40),
    diag_master_lock = ProtoField.bool("profibus.dp.diag.master_lock", "Master_Lock", 8, nil, 0x80),
    diag_s2 = ProtoField.uint8("profibus.dp.diag.status_2", "Station_Status_2", base.HEX),
    diag_prm_req = ProtoField.bool("profibus.dp.diag.prm_req", "Prm_Req", 8, nil, 0x01),
    diag_stat_diag = ProtoField.bool("profibus.dp.diag.stat_diag", "Stat_Diag", 8, nil, 0x02),
    diag_always1 = ProtoField.bool("profibus.dp.diag.always_1", "Always 1", 8, nil, 0x04),
    diag_wd_on = ProtoField.bool("profibus.dp.diag.wd_on", "WD_On", 8, nil, 0x08),
    diag_freeze = ProtoField.bool("profibus.dp.diag.freeze_mode", "Freeze_Mode", 8, nil, 0x10),
    diag_sync = ProtoField.bool("profibus.dp.diag.sync_mode", "Sync_Mode", 8, nil, 0x20),
    diag_s2_res = ProtoField.bool("profibus.dp.diag.status_2_reserved", "Reserved", 8, nil, 0x40),
    diag_deactivated = ProtoField.bool("profibus.dp.diag.deactivated", "Deactivated", 8, nil, 0x80),
    diag_s3 = ProtoField.uint8("profibus.dp.diag.status_3", "Station_Status_3", base.HEX),
    diag_overflow = ProtoField.bool("profibus.dp.diag.ext_diag_overflow", "Ext_Diag_Overflow", 8,
        nil, 0x80),
    diag_master = ProtoField.uint8("profibus.dp.diag.master_add", "Master_Add", base.DEC,
        { [255] = "none" }),
    diag_ext = ProtoField.bytes("profibus.dp.diag.ext_diag_data", "Ext_Diag_Data"),
    diag_block_header = ProtoField.uint8("profibus.dp.diag.block_header", "Block header", base.HEX),
    diag_block_type = ProtoField.uint8("profibus.dp.diag.block_type", "Block type", base.DEC,
        ext_diag_types, 0xC0),
    diag_block_len = ProtoField.uint8("profibus.dp.diag.block_length",
        "Block length (with header)", base.DEC, nil, 0x3F),
    diag_block_data = ProtoField.bytes("profibus.dp.diag.block_data", "Block data"),

    gc_command = ProtoField.uint8("profibus.dp.gc.control_command", "Control_Command", base.HEX),
    gc_clear = ProtoField.bool("profibus.dp.gc.clear_data", "Clear_Data", 8, nil, 0x02),
    gc_unfreeze = ProtoField.bool("profibus.dp.gc.unfreeze", "Unfreeze", 8, nil, 0x04),
    gc_freeze = ProtoField.bool("profibus.dp.gc.freeze", "Freeze", 8, nil, 0x08),
    gc_unsync = ProtoField.bool("profibus.dp.gc.unsync", "Unsync", 8, nil, 0x10),
    gc_sync = ProtoField.bool("profibus.dp.gc.sync", "Sync", 8, nil, 0x20),
    gc_reserved = ProtoField.uint8("profibus.dp.gc.reserved", "Reserved bits", base.HEX, nil, 0xC1),
    gc_group = ProtoField.uint8("profibus.dp.gc.group_select", "Group_Select", base.HEX),

    ssa_new = ProtoField.uint8("profibus.dp.ssa.new_address", "New_Slave_Add", base.DEC),
    ssa_no_chg = ProtoField.uint8("profibus.dp.ssa.no_add_chg", "No_Add_Chg", base.HEX),
    ssa_rem = ProtoField.bytes("profibus.dp.ssa.rem_slave_data", "Rem_Slave_Data"),

    outputs = ProtoField.bytes("profibus.dp.outputs", "Outputs"),
    inputs = ProtoField.bytes("profibus.dp.inputs", "Inputs"),
    data = ProtoField.bytes("profibus.dp.data", "Data"),
    pd_word = ProtoField.uint16("profibus.pd.word", "Process data word", base.HEX),

    -- DFP21B cyclic MOVILINK parameter channel
    ml_mgmt = ProtoField.uint8("profibus.ml.management", "Management", base.HEX),
    ml_service = ProtoField.uint8("profibus.ml.service", "Service", base.DEC, ml_services, 0x0F),
    ml_length = ProtoField.uint8("profibus.ml.length", "Data length", base.DEC, ml_lengths, 0x30),
    ml_handshake = ProtoField.bool("profibus.ml.handshake", "Handshake bit", 8, nil, 0x40),
    ml_status = ProtoField.bool("profibus.ml.status", "Status bit", 8, { "error", "no error" }, 0x80),
    ml_subindex = ProtoField.uint8("profibus.ml.subindex", "Subindex (reserved)", base.HEX),
    ml_index = ProtoField.uint16("profibus.ml.index", "Index", base.DEC_HEX),
    ml_data = ProtoField.uint32("profibus.ml.data", "Data", base.HEX_DEC),
    ml_param = ProtoField.string("profibus.ml.param", "Parameter"),
    ml_error_class = ProtoField.uint8("profibus.ml.error_class", "Error class", base.DEC,
        ml_error_classes),
    ml_error_code = ProtoField.uint8("profibus.ml.error_code", "Error code", base.DEC),
    ml_error_add = ProtoField.uint16("profibus.ml.error_additional", "Additional code", base.HEX),

    -- DP-V1
    dpv1_function = ProtoField.uint8("profibus.dpv1.function", "Function", base.HEX, dpv1_functions),
    dpv1_poll = ProtoField.bool("profibus.dpv1.poll", "Poll (no data)"),
    dpv1_slot = ProtoField.uint8("profibus.dpv1.slot", "Slot", base.DEC),
    dpv1_index = ProtoField.uint8("profibus.dpv1.index", "Index", base.DEC),
    dpv1_length = ProtoField.uint8("profibus.dpv1.length", "Length", base.DEC),
    dpv1_data = ProtoField.bytes("profibus.dpv1.data", "Data"),
    dpv1_error_decode = ProtoField.uint8("profibus.dpv1.error_decode", "Error_Decode", base.HEX,
        dpv1_error_decodes),
    dpv1_error_code1 = ProtoField.uint8("profibus.dpv1.error_code_1", "Error_Code_1", base.HEX),
    dpv1_error_class = ProtoField.uint8("profibus.dpv1.error_class", "Error class", base.HEX,
        dpv1_error_classes, 0xF0),
    dpv1_error_code = ProtoField.uint8("profibus.dpv1.error_code", "Error code", base.DEC, nil, 0x0F),
    dpv1_error_code2 = ProtoField.uint8("profibus.dpv1.error_code_2", "Error_Code_2", base.HEX),
    dpv1_send_timeout = ProtoField.uint16("profibus.dpv1.send_timeout", "Send_Timeout (10 ms)",
        base.DEC),
    dpv1_max_len = ProtoField.uint8("profibus.dpv1.max_len_data_unit", "Max_Len_Data_Unit",
        base.DEC),
    dpv1_features1 = ProtoField.uint8("profibus.dpv1.features_1", "Features_Supported_1", base.HEX),
    dpv1_features2 = ProtoField.uint8("profibus.dpv1.features_2", "Features_Supported_2", base.HEX),
    dpv1_pfeatures1 = ProtoField.uint8("profibus.dpv1.profile_features_1",
        "Profile_Features_Supported_1", base.HEX),
    dpv1_pfeatures2 = ProtoField.uint8("profibus.dpv1.profile_features_2",
        "Profile_Features_Supported_2", base.HEX),
    dpv1_profile = ProtoField.uint16("profibus.dpv1.profile_ident", "Profile_Ident_Number", base.HEX),
    dpv1_s_type = ProtoField.uint8("profibus.dpv1.s_type", "S_Type", base.DEC),
    dpv1_s_len = ProtoField.uint8("profibus.dpv1.s_len", "S_Len", base.DEC),
    dpv1_d_type = ProtoField.uint8("profibus.dpv1.d_type", "D_Type", base.DEC),
    dpv1_d_len = ProtoField.uint8("profibus.dpv1.d_len", "D_Len", base.DEC),
    dpv1_s_addr = ProtoField.bytes("profibus.dpv1.s_addr", "S_Addr"),
    dpv1_d_addr = ProtoField.bytes("profibus.dpv1.d_addr", "D_Addr"),
    dpv1_reserved = ProtoField.bytes("profibus.dpv1.reserved", "Reserved"),
    dpv1_rm_sap = ProtoField.uint8("profibus.dpv1.rm.sap", "Connection SAP", base.DEC),
    dpv1_rm_timeout = ProtoField.uint16("profibus.dpv1.rm.timeout", "Timeout", base.DEC),
    dpv1_abort_subnet = ProtoField.uint8("profibus.dpv1.abort.subnet", "Subnet", base.DEC,
        abort_subnets),
    dpv1_abort_instance = ProtoField.uint8("profibus.dpv1.abort.instance", "Instance", base.DEC,
        abort_instances, 0x30),
    dpv1_abort_reason = ProtoField.uint8("profibus.dpv1.abort.reason", "Reason", base.DEC,
        abort_reasons, 0x0F),
    dpv1_alarm_type = ProtoField.uint8("profibus.dpv1.alarm_type", "Alarm_Type", base.DEC),
    dpv1_specifier = ProtoField.uint8("profibus.dpv1.specifier", "Specifier", base.HEX),

    -- data set 47
    ds47_ref = ProtoField.uint8("profibus.ds47.ref", "Reference", base.DEC),
    ds47_id = ProtoField.uint8("profibus.ds47.id", "ID", base.HEX, ds47_ids),
    ds47_axis = ProtoField.uint8("profibus.ds47.axis", "Axis", base.DEC),
    ds47_n = ProtoField.uint8("profibus.ds47.n_params", "Number of parameters", base.DEC),
    ds47_attribute = ProtoField.uint8("profibus.ds47.attribute", "Attribute", base.HEX),
    ds47_elements = ProtoField.uint8("profibus.ds47.elements", "Number of elements", base.DEC),
    ds47_pnu = ProtoField.uint16("profibus.ds47.pnu", "Parameter number", base.DEC_HEX),
    ds47_param = ProtoField.string("profibus.ds47.param", "Parameter"),
    ds47_subindex = ProtoField.uint16("profibus.ds47.subindex", "Subindex", base.DEC),
    ds47_format = ProtoField.uint8("profibus.ds47.format", "Format", base.HEX, ds47_formats),
    ds47_n_values = ProtoField.uint8("profibus.ds47.n_values", "Number of values", base.DEC),
    ds47_value = ProtoField.uint32("profibus.ds47.value", "Value", base.HEX_DEC),
    ds47_value_bytes = ProtoField.bytes("profibus.ds47.value_bytes", "Value"),
    ds47_error = ProtoField.uint16("profibus.ds47.error", "Error value", base.HEX),
    ds47_pad = ProtoField.uint8("profibus.ds47.pad", "Pad octet", base.HEX),

    -- I&M (index 255)
    im_call = ProtoField.uint8("profibus.im.function", "Extended function number", base.HEX,
        { [0x08] = "call" }),
    im_reserved = ProtoField.uint8("profibus.im.reserved", "Reserved", base.HEX),
    im_fi_index = ProtoField.uint16("profibus.im.fi_index", "FI_Index", base.DEC_HEX, im_records),
    im_header = ProtoField.bytes("profibus.im.header", "Manufacturer header"),
    im_manufacturer = ProtoField.uint16("profibus.im.manufacturer_id", "MANUFACTURER_ID", base.HEX),
    im_order = ProtoField.string("profibus.im.order_id", "ORDER_ID"),
    im_serial = ProtoField.string("profibus.im.serial_number", "SERIAL_NUMBER"),
    im_hw_rev = ProtoField.uint16("profibus.im.hardware_revision", "HARDWARE_REVISION", base.DEC),
    im_sw_rev = ProtoField.string("profibus.im.software_revision", "SOFTWARE_REVISION"),
    im_rev_counter = ProtoField.uint16("profibus.im.rev_counter", "REV_COUNTER", base.DEC),
    im_profile = ProtoField.uint16("profibus.im.profile_id", "PROFILE_ID", base.HEX),
    im_profile_type = ProtoField.uint16("profibus.im.profile_specific_type",
        "PROFILE_SPECIFIC_TYPE", base.HEX),
    im_version = ProtoField.uint16("profibus.im.version", "IM_VERSION", base.HEX),
    im_supported = ProtoField.uint16("profibus.im.supported", "IM_SUPPORTED", base.HEX),
    im_record = ProtoField.bytes("profibus.im.record", "Record"),
}
local field_list = {}
for _, f in pairs(F) do field_list[#field_list + 1] = f end
proto.fields = field_list

local E = {
    malformed = ProtoExpert.new("profibus.malformed", "Malformed telegram",
        expert.group.MALFORMED, expert.severity.ERROR),
    fcs = ProtoExpert.new("profibus.fcs.bad", "FCS mismatch", expert.group.CHECKSUM,
        expert.severity.ERROR),
    trailing = ProtoExpert.new("profibus.trailing.expert", "Octets after the end delimiter",
        expert.group.MALFORMED, expert.severity.WARN),
    negative = ProtoExpert.new("profibus.negative", "Negative FDL response",
        expert.group.RESPONSE_CODE, expert.severity.WARN),
    diag_pending = ProtoExpert.new("profibus.diag_pending", "Slave signals new diagnosis (DH)",
        expert.group.RESPONSE_CODE, expert.severity.NOTE),
    repeat_ = ProtoExpert.new("profibus.repeat", "Repetition: FCB unchanged", expert.group.SEQUENCE,
        expert.severity.NOTE),
    dpv1_negative = ProtoExpert.new("profibus.dpv1.negative", "Negative DP-V1 response",
        expert.group.RESPONSE_CODE, expert.severity.WARN),
    ds47_error = ProtoExpert.new("profibus.ds47.negative", "Negative parameter response",
        expert.group.RESPONSE_CODE, expert.severity.WARN),
    internal = ProtoExpert.new("profibus.internal_error", "Internal error in profibus.lua",
        expert.group.UNDECODED, expert.severity.ERROR),
}
proto.experts = { E.malformed, E.fcs, E.trailing, E.negative, E.diag_pending, E.repeat_,
    E.dpv1_negative, E.ds47_error, E.internal }

proto.prefs.dfp21b_movilink = Pref.bool(
    "DFP21B: first 8 octets of Data_Exchange are the MOVILINK channel", true,
    "Decode the first 8 octets of a Data_Exchange with 8 or more octets as the DFP21B's cyclic "
    .. "MOVILINK parameter channel and the rest as process data words. When the capture holds "
    .. "a Chk_Cfg for the slave, it decides instead (channel present if it starts with F3 or B7 "
    .. "followed by more identifiers). Off: never.")

------------------------------------------------------------------------------------------------
-- State across telegrams, built on the first pass and looked up by frame number afterwards
-- (Wireshark re-dissects frames in any order once they have been seen).

local state = {}
local function reset_state()
    state = {
        pending = nil,          -- last request that expects an answer
        response_to = {},       -- response frame -> { num, service }
        response_in = {},       -- request frame -> response frame
        fcb = {},               -- "sa>da" -> last FCB of an FCV=1 request
        repeat_ = {},           -- frame -> true when FCB was unchanged
        channel = {},           -- slave address -> { present, frame } from Chk_Cfg
        channel_at = {},        -- Data_Exchange frame -> { present, frame } or false
    }
end
reset_state()
function proto.init() reset_state() end

------------------------------------------------------------------------------------------------
-- Bounded reading. take() raises a table (not a string) when the telegram ends early; the
-- dissector catches exactly that and turns it into a "malformed" expert info.

local Truncated = {}
local Reader = {}
Reader.__index = Reader
local function reader(tvb, off, stop) return setmetatable({ tvb = tvb, off = off, stop = stop }, Reader) end
function Reader:left() return self.stop - self.off end
function Reader:take(n, what)
    if n <= 0 or self.off + n > self.stop then
        error(setmetatable({ what = what, need = n, have = self.stop - self.off }, Truncated), 0)
    end
    local r = self.tvb(self.off, n)
    self.off = self.off + n
    return r
end
function Reader:rest() local n = self:left(); if n <= 0 then return nil end return self:take(n, "rest") end
function Reader:peek() if self.off >= self.stop then return nil end return self.tvb(self.off, 1):uint() end

local function hex_of(range)
    local parts = {}
    local n = range:len()
    for i = 0, math.min(n, 16) - 1 do parts[#parts + 1] = string.format("%02X", range(i, 1):uint()) end
    if n > 16 then parts[#parts + 1] = "..." end
    return table.concat(parts, " ")
end

local function note(st, text) st.summary[#st.summary + 1] = text end

local function malformed(st, tree, text)
    st.malformed = true
    tree:add_proto_expert_info(E.malformed, "Malformed: " .. text)
    note(st, "[malformed: " .. text .. "]")
end

local function add_bits(tree, range, fields)
    for _, f in ipairs(fields) do tree:add(f, range) end
end

------------------------------------------------------------------------------------------------
-- DP-V0 services

local function decode_cfg(st, tree, c, label)
    local ctree = tree:add(proto, c.tvb(c.off, c:left()), label)
    local total_in, total_out, ids = 0, 0, {}
    local first_range = c.tvb(c.off, c:left())
    while c:left() > 0 do
        local start = c.off
        local r = c:take(1, "identifier")
        local v = r:uint()
        ids[#ids + 1] = string.format("%02X", v)
        local it = ctree:add(F.cfg_id, r)
        local dir = bits(v, 4, 2)
        local in_n, out_n = 0, 0
        if dir ~= 0 then
            local unit = has(v, 0x40) and 2 or 1
            local n = (bits(v, 0, 4) + 1) * unit
            if dir == 1 or dir == 3 then in_n = n end
            if dir == 2 or dir == 3 then out_n = n end
            add_bits(it, r, { F.cfg_consistency, F.cfg_words, F.cfg_direction, F.cfg_length })
            it:append_text(string.format(" (%s %d %s%s)", cfg_directions[dir],
                bits(v, 0, 4) + 1, unit == 2 and "word(s)" or "byte(s)",
                has(v, 0x80) and ", consistent" or ""))
        else
            add_bits(it, r, { F.cfg_special, F.cfg_manuf_len })
            local kind, manuf = bits(v, 6, 2), bits(v, 0, 4)
            if kind == 0 and manuf == 0 then
                it:append_text(" (free place)")
            else
                it:append_text(" (special format: " .. cfg_special[kind] .. ")")
            end
            local function length_octet(what)
                local lr = c:take(1, "special format " .. what .. " length octet")
                local lv = lr:uint()
                local lit = it:add(F.cfg_len_octet, lr)
                add_bits(lit, lr, { F.cfg_len_consistency, F.cfg_len_words, F.cfg_len_code })
                local n = (bits(lv, 0, 6) + 1) * (has(lv, 0x40) and 2 or 1)
                lit:append_text(string.format(" (%s %d octets)", what, n))
                return n
            end
            if kind == 2 or kind == 3 then out_n = length_octet("output") end
            if kind == 1 or kind == 3 then in_n = length_octet("input") end
            -- 15 = no manufacturer data, check may be omitted (Chk_Cfg only)
            if manuf > 0 and manuf < 15 then it:add(F.cfg_manuf, c:take(manuf, "manufacturer data")) end
        end
        if in_n > 0 then it:add(F.cfg_in, r, in_n):set_generated() end
        if out_n > 0 then it:add(F.cfg_out, r, out_n):set_generated() end
        total_in, total_out = total_in + in_n, total_out + out_n
        it:set_len(c.off - start)
    end
    ctree:add(F.cfg_total_in, first_range, total_in):set_generated()
    ctree:add(F.cfg_total_out, first_range, total_out):set_generated()
    local text = string.format("%s (in %d, out %d octets)", table.concat(ids, " "), total_in, total_out)
    ctree:append_text(": " .. text)
    note(st, text)
    return ids
end

local function decode_set_prm(st, tree, c)
    local r = c:take(1, "Station_Status")
    local v = r:uint()
    local it = tree:add(F.prm_status, r)
    add_bits(it, r, { F.prm_lock, F.prm_unlock, F.prm_sync, F.prm_freeze, F.prm_wd_on, F.prm_status_res })
    local flags = {}
    if has(v, 0x80) then flags[#flags + 1] = "Lock" end
    if has(v, 0x40) then flags[#flags + 1] = "Unlock" end
    if has(v, 0x20) then flags[#flags + 1] = "Sync_Req" end
    if has(v, 0x10) then flags[#flags + 1] = "Freeze_Req" end
    if has(v, 0x08) then flags[#flags + 1] = "WD_On" end
    if #flags > 0 then note(st, table.concat(flags, "|")) end
    local r1, r2 = c:take(1, "WD_Fact_1"), c:take(1, "WD_Fact_2")
    tree:add(F.prm_wd1, r1)
    tree:add(F.prm_wd2, r2)
    local rt = c:take(1, "min TSDR")
    tree:add(F.prm_tsdr, rt)
    local ri = c:take(2, "Ident_Number")
    tree:add(F.ident, ri)
    local rg = c:take(1, "Group_Ident")
    tree:add(F.prm_group, rg)
    local wd_base = 10
    if c:left() >= 3 then
        local d1, d2, d3 = c:take(1, "DPV1_Status_1"), c:take(1, "DPV1_Status_2"), c:take(1, "DPV1_Status_3")
        local i1 = tree:add(F.prm_dpv1_1, d1)
        add_bits(i1, d1, { F.prm_dpv1_enable, F.prm_fail_safe, F.prm_publisher, F.prm_wd_base,
            F.prm_dis_stop, F.prm_dis_start })
        local i2 = tree:add(F.prm_dpv1_2, d2)
        add_bits(i2, d2, { F.prm_al_pull, F.prm_al_process, F.prm_al_diag, F.prm_al_manuf,
            F.prm_al_status, F.prm_al_update, F.prm_chk_cfg_mode })
        local i3 = tree:add(F.prm_dpv1_3, d3)
        add_bits(i3, d3, { F.prm_prmcmd, F.prm_isom, F.prm_structure, F.prm_alarm_mode })
        if has(d1:uint(), 0x04) then wd_base = 1 end
        if has(d1:uint(), 0x80) then note(st, "DPV1_Enable") end
    end
    local ms = r1:uint() * r2:uint() * wd_base
    local wit = tree:add(F.prm_wd_ms, c.tvb(r1:offset(), 2), ms)
    wit:set_generated()
    if has(v, 0x08) then note(st, string.format("WD %d ms", ms)) end
    note(st, string.format("min TSDR %d ident 0x%04X", rt:uint(), ri:uint()))
    if c:left() > 0 then
        local ru = c:rest()
        local uit = tree:add(F.prm_user, ru)
        -- The DFP21B's own block (protocol.md §B4): 06 81 00 00 01 flag.
        if ri:uint() == 0x6003 and ru:len() == 6 and ru(0, 1):uint() == 0x06
                and ru(1, 1):uint() == 0x81 then
            uit:append_text(" (DFP21B: structured block len 6, type 0x81 user, slot 0, version "
                .. ru(4, 1):uint() .. ")")
            uit:add(F.prm_dfp21b_alarm, ru(5, 1), ru(5, 1):uint() == 0)
        end
        note(st, "user prm " .. hex_of(ru))
    end
end

local function decode_slave_diag(st, tree, c)
    local r1 = c:take(1, "Station_Status_1")
    local r2 = c:take(1, "Station_Status_2")
    local r3 = c:take(1, "Station_Status_3")
    local i1 = tree:add(F.diag_s1, r1)
    add_bits(i1, r1, { F.diag_non_existent, F.diag_not_ready, F.diag_cfg_fault, F.diag_ext_diag,
        F.diag_not_supported, F.diag_invalid_resp, F.diag_prm_fault, F.diag_master_lock })
    local i2 = tree:add(F.diag_s2, r2)
    add_bits(i2, r2, { F.diag_prm_req, F.diag_stat_diag, F.diag_always1, F.diag_wd_on,
        F.diag_freeze, F.diag_sync, F.diag_s2_res, F.diag_deactivated })
    local i3 = tree:add(F.diag_s3, r3)
    i3:add(F.diag_overflow, r3)
    local names1 = { [0x01] = "Station_Non_Existent", [0x02] = "Station_Not_Ready",
        [0x04] = "Cfg_Fault", [0x08] = "Ext_Diag", [0x10] = "Not_Supported",
        [0x20] = "Invalid_Slave_Response", [0x40] = "Prm_Fault", [0x80] = "Master_Lock" }
    local names2 = { [0x01] = "Prm_Req", [0x02] = "Stat_Diag", [0x08] = "WD_On",
        [0x10] = "Freeze_Mode", [0x20] = "Sync_Mode", [0x80] = "Deactivated" }
    local set = {}
    for _, m in ipairs({ 0x01, 0x02, 0x04, 0x08, 0x10, 0x20, 0x40, 0x80 }) do
        if names1[m] and has(r1:uint(), m) then set[#set + 1] = names1[m] end
    end
    for _, m in ipairs({ 0x01, 0x02, 0x08, 0x10, 0x20, 0x80 }) do
        if names2[m] and has(r2:uint(), m) then set[#set + 1] = names2[m] end
    end
    if has(r3:uint(), 0x80) then set[#set + 1] = "Ext_Diag_Overflow" end
    if #set > 0 then note(st, table.concat(set, " ")) end
    local rm = c:take(1, "Master_Add")
    tree:add(F.diag_master, rm)
    local ri = c:take(2, "Ident_Number")
    tree:add(F.ident, ri)
    note(st, string.format("master %s ident 0x%04X",
        rm:uint() == 255 and "none" or tostring(rm:uint()), ri:uint()))
    if c:left() > 0 then
        local all = c.tvb(c.off, c:left())
        local et = tree:add(F.diag_ext, all)
        note(st, "ext diag " .. hex_of(all))
        while c:left() > 0 do
            local hr = c:take(1, "ext diag block header")
            local h = hr:uint()
            local len = bits(h, 0, 6)
            local bt = et:add(F.diag_block_header, hr)
            add_bits(bt, hr, { F.diag_block_type, F.diag_block_len })
            bt:append_text(string.format(" (%s, %d octets)", ext_diag_types[bits(h, 6, 2)], len))
            if bits(h, 6, 2) == 1 then
                -- identifier-related: the length is the header plus the bit map
                if len > 1 then bt:add(F.diag_block_data, c:take(len - 1, "ext diag block")) end
            elseif len == 0 then
                malformed(st, bt, "ext diag block length 0")
                return
            elseif len > 1 then
                bt:add(F.diag_block_data, c:take(len - 1, "ext diag block"))
            end
        end
    end
end

local function decode_global_control(st, tree, c)
    local r = c:take(1, "Control_Command")
    local v = r:uint()
    local it = tree:add(F.gc_command, r)
    add_bits(it, r, { F.gc_sync, F.gc_unsync, F.gc_freeze, F.gc_unfreeze, F.gc_clear, F.gc_reserved })
    local cmds = {}
    for _, p in ipairs({ { 0x20, "Sync" }, { 0x10, "Unsync" }, { 0x08, "Freeze" },
            { 0x04, "Unfreeze" }, { 0x02, "Clear_Data" } }) do
        if has(v, p[1]) then cmds[#cmds + 1] = p[2] end
    end
    local text = #cmds > 0 and table.concat(cmds, "|") or "Operate (no command)"
    it:append_text(" (" .. text .. ")")
    local rg = c:take(1, "Group_Select")
    tree:add(F.gc_group, rg)
    note(st, string.format("%s group 0x%02X", text, rg:uint()))
end

local function decode_set_slave_add(st, tree, c)
    local rn = c:take(1, "New_Slave_Add")
    tree:add(F.ssa_new, rn)
    local ri = c:take(2, "Ident_Number")
    tree:add(F.ident, ri)
    tree:add(F.ssa_no_chg, c:take(1, "No_Add_Chg"))
    if c:left() > 0 then tree:add(F.ssa_rem, c:rest()) end
    note(st, string.format("new address %d ident 0x%04X", rn:uint(), ri:uint()))
end

-- The DFP21B's 8-octet parameter channel (protocol.md §B6), request or reply.
local function decode_movilink_channel(st, tree, c, is_request, source)
    local all = c.tvb(c.off, 8)
    local mt = tree:add(proto, all, "MOVILINK parameter channel")
    if source then mt:append_text(" (" .. source .. ")") end
    local rm = c:take(1, "management")
    local m = rm:uint()
    local mit = mt:add(F.ml_mgmt, rm)
    add_bits(mit, rm, { F.ml_status, F.ml_handshake, F.ml_length, F.ml_service })
    mt:add(F.ml_subindex, c:take(1, "subindex"))
    local ri = c:take(2, "index")
    local iit = mt:add(F.ml_index, ri)
    local pname = ml_param_names[ri:uint()]
    if pname then
        iit:append_text(" (" .. pname .. ")")
        mt:add(F.ml_param, ri, pname)
    end
    local rd = c:take(4, "data")
    local service = bits(m, 0, 4)
    local text = string.format("ML %s %s HS=%d", ml_services[service] or
        string.format("service %d", service), ml_index_text(ri:uint()), bits(m, 6, 1))
    if has(m, 0x80) then
        local class, code, add = rd(0, 1):uint(), rd(1, 1):uint(), rd(2, 2):uint()
        mt:add(F.ml_error_class, rd(0, 1))
        mt:add(F.ml_error_code, rd(1, 1))
        local ait = mt:add(F.ml_error_add, rd(2, 2))
        local meaning = ""
        if class == 8 and ml_class8_codes[bits(add, 0, 8)] then
            meaning = ml_class8_codes[bits(add, 0, 8)]
            ait:append_text(" (" .. meaning .. ")")
        end
        text = text .. string.format(" error class %d code %d add 0x%04X%s", class, code, add,
            meaning ~= "" and (" " .. meaning) or "")
    else
        mt:add(F.ml_data, rd)
        if service ~= 0 and (not is_request or service == 2 or service == 3) then
            text = text .. string.format(" = 0x%08X", rd:uint())
        end
    end
    mt:append_text(": " .. text)
    note(st, text)
end

local function decode_process_data(st, tree, c, is_request)
    if c:left() <= 0 then return end
    local pt = tree:add(proto, c.tvb(c.off, c:left()), is_request and "Process output words"
        or "Process input words")
    local words = {}
    local i = 1
    while c:left() >= 2 do
        local r = c:take(2, "process data word")
        pt:add(F.pd_word, r):prepend_text((is_request and "PO" or "PI") .. i .. " ")
        words[#words + 1] = string.format("%04X", r:uint())
        i = i + 1
    end
    if c:left() == 1 then pt:add(F.data, c:take(1, "odd octet")):append_text(" (odd octet)") end
    note(st, (is_request and "PO " or "PI ") .. table.concat(words, " "))
end

local function cfg_has_channel(ids)
    return #ids >= 2 and (ids[1] == "F3" or ids[1] == "B7")
end

local function decode_data_exchange(st, tree, c, is_request, slave)
    local n = c:left()
    note(st, string.format("%d octets", n))
    if n == 0 then return end
    tree:add(is_request and F.outputs or F.inputs, c.tvb(c.off, n))
    if not proto.prefs.dfp21b_movilink or n < 8 then return end
    local known
    if not st.pinfo.visited then
        known = state.channel[slave] or false
        state.channel_at[st.pinfo.number] = known
    else
        known = state.channel_at[st.pinfo.number] or false
    end
    local source = "preference"
    if known then
        if not known.present then return end
        source = "Chk_Cfg in frame " .. known.frame
    end
    decode_movilink_channel(st, tree, c, is_request, source)
    decode_process_data(st, tree, c, is_request)
end

------------------------------------------------------------------------------------------------
-- Data set 47 (PROFIdrive base mode parameter access, DFP21B MOVILINK variant)

local function is_movilink_id(id) return id == 0x40 or id == 0xC0 end

local function decode_ds47_values(st, tree, c, id, count_limit, texts)
    local blocks = 0
    while c:left() > 0 and (count_limit == nil or blocks < count_limit) do
        local rf = c:take(1, "value format")
        local fmt = rf:uint()
        local size = ds47_format_sizes[fmt]
        local bt = tree:add(proto, rf, string.format("Values %d", blocks + 1))
        bt:add(F.ds47_format, rf)
        if size == nil then
            malformed(st, bt, string.format("unknown value format 0x%02X", fmt))
            return
        end
        local rn = c:take(1, "number of values")
        local count = rn:uint()
        bt:add(F.ds47_n_values, rn)
        local nbytes = size * count
        if fmt == 0x40 then
            texts[#texts + 1] = "ok"
        elseif fmt == 0x09 or fmt == 0x0A then
            if nbytes > 0 then bt:add(F.ds47_value_bytes, c:take(nbytes, "values")) end
            texts[#texts + 1] = string.format("%d octets", nbytes)
        else
            for k = 1, count do
                local rv = c:take(size, "value")
                local v = rv:uint()
                if fmt == 0x44 then
                    local et = bt:add(F.ds47_error, rv)
                    if k == 1 then
                        local meaning = is_movilink_id(id) and movilink_error_text(v)
                            or profidrive_error_text(v)
                        et:append_text(" (" .. meaning .. ")")
                        et:add_proto_expert_info(E.ds47_error, string.format(
                            "Parameter error 0x%04X: %s", v, meaning))
                        texts[#texts + 1] = string.format("error 0x%04X", v)
                    else
                        et:prepend_text("Additional information: ")
                    end
                else
                    bt:add(F.ds47_value, rv)
                    texts[#texts + 1] = string.format(size == 4 and "0x%08X" or
                        (size == 2 and "0x%04X" or "0x%02X"), v)
                end
            end
        end
        bt:set_len(2 + nbytes)
        -- PROFIdrive pads odd value octets to words; no format is 0, so a 0 octet is padding.
        if nbytes % 2 == 1 and c:peek() == 0 then bt:add(F.ds47_pad, c:take(1, "pad")) end
        blocks = blocks + 1
    end
    return blocks
end

local function decode_ds47_request(st, tree, c)
    local t = tree:add(proto, c.tvb(c.off, c:left()), "PROFIdrive parameter request (data set 47)")
    local rr = c:take(1, "request reference")
    t:add(F.ds47_ref, rr)
    local ri = c:take(1, "request ID")
    local id = ri:uint()
    t:add(F.ds47_id, ri)
    local raxis = c:take(1, "axis")
    t:add(F.ds47_axis, raxis)
    local rn = c:take(1, "number of parameters")
    local n = rn:uint()
    t:add(F.ds47_n, rn)
    local writes, params = 0, {}
    for p = 1, n do
        local at = t:add(proto, c.tvb(c.off, math.min(6, c:left())), "Parameter address " .. p)
        local ra = c:take(1, "attribute")
        local a = ra:uint()
        local ait = at:add(F.ds47_attribute, ra)
        local what
        if is_movilink_id(id) then
            what = movilink_attributes[bits(a, 4, 4) * 16] or "reserved service"
            ait:append_text(" (MOVILINK " .. what .. ")")
            if bits(a, 4, 4) == 2 or bits(a, 4, 4) == 3 then writes = writes + 1 end
        else
            what = profidrive_attributes[a] or "unknown attribute"
            ait:append_text(" (" .. what .. ")")
        end
        at:add(F.ds47_elements, c:take(1, "number of elements"))
        local rp = c:take(2, "parameter number")
        local pit = at:add(F.ds47_pnu, rp)
        local pname = ml_param_names[rp:uint()]
        if pname then
            pit:append_text(" (" .. pname .. ")")
            at:add(F.ds47_param, rp, pname)
        end
        at:add(F.ds47_subindex, c:take(2, "subindex"))
        local ptext = string.format("%s %s", is_movilink_id(id) and what or "PNU",
            ml_index_text(rp:uint()))
        at:append_text(": " .. ptext)
        params[#params + 1] = ptext
    end
    if id == 0x02 then writes = n end
    local values = {}
    if writes > 0 then decode_ds47_values(st, t, c, id, writes, values) end
    local text = string.format("DS47 ref %d %s axis %d: %s", rr:uint(),
        ds47_ids[id] or string.format("id 0x%02X", id), raxis:uint(),
        table.concat(params, ", "))
    if #values > 0 then text = text .. " = " .. table.concat(values, ", ") end
    t:append_text(": " .. text)
    note(st, text)
    if c:left() > 0 then
        malformed(st, t, string.format("%d octets after the parameter request", c:left()))
    end
end

local function decode_ds47_response(st, tree, c)
    local t = tree:add(proto, c.tvb(c.off, c:left()), "PROFIdrive parameter response (data set 47)")
    local rr = c:take(1, "response reference")
    t:add(F.ds47_ref, rr)
    local ri = c:take(1, "response ID")
    local id = ri:uint()
    t:add(F.ds47_id, ri)
    local raxis = c:take(1, "axis")
    t:add(F.ds47_axis, raxis)
    local rn = c:take(1, "number of parameters")
    t:add(F.ds47_n, rn)
    local values = {}
    decode_ds47_values(st, t, c, id, rn:uint(), values)
    local text = string.format("DS47 ref %d %s axis %d: %d parameter(s)", rr:uint(),
        ds47_ids[id] or string.format("id 0x%02X", id), raxis:uint(), rn:uint())
    if #values > 0 then text = text .. " " .. table.concat(values, ", ") end
    t:append_text(": " .. text)
    note(st, text)
    if has(id, 0x80) then t:add_proto_expert_info(E.ds47_error, "Negative parameter response") end
    if c:left() > 0 then
        malformed(st, t, string.format("%d octets after the parameter response", c:left()))
    end
end

local function decode_im(st, tree, c)
    local t = tree:add(proto, c.tvb(c.off, c:left()), "I&M call")
    t:add(F.im_call, c:take(1, "I&M function"))
    t:add(F.im_reserved, c:take(1, "I&M reserved"))
    local rf = c:take(2, "FI_Index")
    t:add(F.im_fi_index, rf)
    local name = im_records[rf:uint()] or string.format("FI_Index %d", rf:uint())
    note(st, name)
    t:append_text(": " .. name)
    if c:left() == 0 then return end
    if rf:uint() == 0xFDE8 and c:left() >= 64 then
        local rt = t:add(proto, c.tvb(c.off, 64), "I&M0 record")
        rt:add(F.im_header, c:take(10, "I&M0 header"))
        local rman = c:take(2, "MANUFACTURER_ID")
        rt:add(F.im_manufacturer, rman)
        local ro = c:take(20, "ORDER_ID")
        rt:add(F.im_order, ro)
        rt:add(F.im_serial, c:take(16, "SERIAL_NUMBER"))
        rt:add(F.im_hw_rev, c:take(2, "HARDWARE_REVISION"))
        local rs = c:take(4, "SOFTWARE_REVISION")
        local first = rs(0, 1):uint()
        local sw = string.format("%s%d.%d.%d", (first >= 0x20 and first < 0x7F) and
            string.char(first) or "?", rs(1, 1):uint(), rs(2, 1):uint(), rs(3, 1):uint())
        rt:add(F.im_sw_rev, rs, sw)
        rt:add(F.im_rev_counter, c:take(2, "REV_COUNTER"))
        rt:add(F.im_profile, c:take(2, "PROFILE_ID"))
        rt:add(F.im_profile_type, c:take(2, "PROFILE_SPECIFIC_TYPE"))
        rt:add(F.im_version, c:take(2, "IM_VERSION"))
        rt:add(F.im_supported, c:take(2, "IM_SUPPORTED"))
        note(st, string.format("manufacturer 0x%04X order %s software %s", rman:uint(),
            ro:string():gsub("%s+$", ""), sw))
    end
    if c:left() > 0 then t:add(F.im_record, c:rest()) end
end

------------------------------------------------------------------------------------------------
-- DP-V1 PDUs (MSAC1 on SAP 51/50, MSAC2 on SAP 49 and the connection SAPs)

local function decode_dpv1(st, tree, c, is_request)
    if c:left() == 0 then
        if is_request then
            tree:add(F.dpv1_poll, c.tvb(c.off - 1, 1), true):set_generated()
            note(st, "poll")
        end
        return
    end
    local t = tree:add(proto, c.tvb(c.off, c:left()), "DP-V1")
    local rfn = c:take(1, "function")
    local fn = rfn:uint()
    t:add(F.dpv1_function, rfn)
    local base_fn = fn % 128
    local name = dpv1_functions[base_fn] or string.format("function 0x%02X", fn)
    local suffix = is_request and ".req" or ".res"
    if fn >= 0x80 then
        if is_request then
            malformed(st, t, string.format("negative function code 0x%02X in a request", fn))
            return
        end
        local rd = c:take(1, "Error_Decode")
        t:add(F.dpv1_error_decode, rd)
        local re1 = c:take(1, "Error_Code_1")
        local eit = t:add(F.dpv1_error_code1, re1)
        add_bits(eit, re1, { F.dpv1_error_class, F.dpv1_error_code })
        local meaning = dpv1_error_text(re1:uint())
        eit:append_text(" (" .. meaning .. ")")
        t:add(F.dpv1_error_code2, c:take(1, "Error_Code_2"))
        local text = string.format("%s.res negative: 0x%02X %s", name, re1:uint(), meaning)
        t:add_proto_expert_info(E.dpv1_negative, text)
        t:append_text(": " .. text)
        note(st, text)
        if c:left() > 0 then t:add(F.dpv1_data, c:rest()) end
        return
    end
    if base_fn == 0x5E or base_fn == 0x5F or base_fn == 0x51 then
        local rs, ri, rl = c:take(1, "slot"), c:take(1, "index"), c:take(1, "length")
        t:add(F.dpv1_slot, rs)
        t:add(F.dpv1_index, ri)
        t:add(F.dpv1_length, rl)
        local index, len = ri:uint(), rl:uint()
        local text = string.format("%s%s slot %d index %d length %d", name, suffix, rs:uint(), index, len)
        t:append_text(": " .. text)
        note(st, text)
        local carries = (base_fn == 0x5E and not is_request) or (base_fn == 0x5F and is_request)
            or base_fn == 0x51
        if not carries then
            if c:left() > 0 then malformed(st, t, string.format("%d octets after the %s%s header",
                c:left(), name, suffix)) end
            return
        end
        if c:left() ~= len then
            malformed(st, t, string.format("length %d but %d data octets", len, c:left()))
            return
        end
        if len == 0 then return end
        local data = reader(c.tvb, c.off, c.off + len)
        t:add(F.dpv1_data, c.tvb(c.off, len))
        c.off = c.off + len
        if index == 47 and base_fn == 0x5F then
            decode_ds47_request(st, t, data)
        elseif index == 47 and base_fn == 0x5E then
            decode_ds47_response(st, t, data)
        elseif index == 255 then
            decode_im(st, t, data)
        end
    elseif base_fn == 0x57 and is_request then
        t:add(F.dpv1_reserved, c:take(3, "Initiate reserved"))
        local rto = c:take(2, "Send_Timeout")
        t:add(F.dpv1_send_timeout, rto)
        t:add(F.dpv1_features1, c:take(1, "Features_Supported_1"))
        t:add(F.dpv1_features2, c:take(1, "Features_Supported_2"))
        t:add(F.dpv1_pfeatures1, c:take(1, "Profile_Features_Supported_1"))
        t:add(F.dpv1_pfeatures2, c:take(1, "Profile_Features_Supported_2"))
        t:add(F.dpv1_profile, c:take(2, "Profile_Ident_Number"))
        t:add(F.dpv1_s_type, c:take(1, "S_Type"))
        local rsl = c:take(1, "S_Len")
        t:add(F.dpv1_s_len, rsl)
        t:add(F.dpv1_d_type, c:take(1, "D_Type"))
        local rdl = c:take(1, "D_Len")
        t:add(F.dpv1_d_len, rdl)
        if rsl:uint() > 0 then t:add(F.dpv1_s_addr, c:take(rsl:uint(), "S_Addr")) end
        if rdl:uint() > 0 then t:add(F.dpv1_d_addr, c:take(rdl:uint(), "D_Addr")) end
        local text = string.format("Initiate.req Send_Timeout %d ms", rto:uint() * 10)
        t:append_text(": " .. text)
        note(st, text)
        if c:left() > 0 then t:add(F.dpv1_data, c:rest()) end
    elseif base_fn == 0x57 then
        local rml = c:take(1, "Max_Len_Data_Unit")
        t:add(F.dpv1_max_len, rml)
        t:add(F.dpv1_features1, c:take(1, "Features_Supported_1"))
        t:add(F.dpv1_features2, c:take(1, "Features_Supported_2"))
        t:add(F.dpv1_pfeatures1, c:take(1, "Profile_Features_Supported_1"))
        t:add(F.dpv1_pfeatures2, c:take(1, "Profile_Features_Supported_2"))
        t:add(F.dpv1_profile, c:take(2, "Profile_Ident_Number"))
        t:add(F.dpv1_s_type, c:take(1, "S_Type"))
        local rsl = c:take(1, "S_Len")
        t:add(F.dpv1_s_len, rsl)
        t:add(F.dpv1_d_type, c:take(1, "D_Type"))
        local rdl = c:take(1, "D_Len")
        t:add(F.dpv1_d_len, rdl)
        if rsl:uint() > 0 then t:add(F.dpv1_s_addr, c:take(rsl:uint(), "S_Addr")) end
        if rdl:uint() > 0 then t:add(F.dpv1_d_addr, c:take(rdl:uint(), "D_Addr")) end
        local text = string.format("Initiate.res Max_Len_Data_Unit %d", rml:uint())
        t:append_text(": " .. text)
        note(st, text)
        if c:left() > 0 then t:add(F.dpv1_data, c:rest()) end
    elseif base_fn == 0x56 then
        local rsap = c:take(1, "connection SAP")
        t:add(F.dpv1_rm_sap, rsap)
        t:add(F.dpv1_rm_timeout, c:take(2, "RM timeout"))
        local text = string.format("Initiate RM%s: use SAP %d", suffix, rsap:uint())
        t:append_text(": " .. text)
        note(st, text)
    elseif base_fn == 0x58 then
        t:add(F.dpv1_abort_subnet, c:take(1, "Abort subnet"))
        local rr = c:take(1, "Abort instance/reason")
        t:add(F.dpv1_abort_instance, rr)
        t:add(F.dpv1_abort_reason, rr)
        if c:left() > 0 then t:add(F.dpv1_reserved, c:take(1, "Abort reserved")) end
        local v = rr:uint()
        local text = string.format("Abort%s %s %s", suffix, abort_instances[bits(v, 4, 2)] or "instance?",
            abort_reasons[bits(v, 0, 4)] or string.format("reason %d", bits(v, 0, 4)))
        t:append_text(": " .. text)
        note(st, text)
    elseif base_fn == 0x48 then
        if c:left() > 0 then t:add(F.dpv1_data, c:rest()) end
        note(st, "Idle" .. suffix)
        t:append_text(": Idle" .. suffix)
    elseif base_fn == 0x5C then
        local rs = c:take(1, "slot")
        t:add(F.dpv1_slot, rs)
        t:add(F.dpv1_alarm_type, c:take(1, "Alarm_Type"))
        t:add(F.dpv1_specifier, c:take(1, "Specifier"))
        note(st, string.format("Alarm_Ack%s slot %d", suffix, rs:uint()))
    else
        if c:left() > 0 then t:add(F.dpv1_data, c:rest()) end
        note(st, name .. suffix)
        t:append_text(": " .. name .. suffix)
    end
end

------------------------------------------------------------------------------------------------
-- Service dispatch

local function decode_service(st, tree, c, service, is_request)
    if service == "Data_Exchange" then
        decode_data_exchange(st, tree, c, is_request, is_request and st.da or st.sa)
        return
    end
    if service == "Set_Prm" and is_request then return decode_set_prm(st, tree, c) end
    if service == "Chk_Cfg" and is_request then
        local ids = decode_cfg(st, tree, c, "Configuration (Chk_Cfg)")
        if not st.pinfo.visited and not st.malformed then
            state.channel[st.da] = { present = cfg_has_channel(ids), frame = st.pinfo.number }
        end
        return
    end
    if service == "Get_Cfg" and not is_request and c:left() > 0 then
        decode_cfg(st, tree, c, "Configuration (Get_Cfg)")
        return
    end
    if service == "Slave_Diag" and not is_request and c:left() > 0 then
        return decode_slave_diag(st, tree, c)
    end
    if service == "Global_Control" and is_request then return decode_global_control(st, tree, c) end
    if service == "Set_Slave_Add" and is_request then return decode_set_slave_add(st, tree, c) end
    if (service == "Rd_Inp" or service == "Rd_Outp") and not is_request and c:left() > 0 then
        local n = c:left()
        tree:add(service == "Rd_Inp" and F.inputs or F.outputs, c:rest())
        note(st, string.format("%d octets", n))
        return
    end
    if service == "MSAC1" or service == "MSAC1_Alarm" or service == "MSAC2" or service == "MSAC2_RM" then
        return decode_dpv1(st, tree, c, is_request)
    end
    if c:left() > 0 then
        local n = c:left()
        tree:add(F.data, c:rest())
        note(st, string.format("%d octets", n))
    end
end

------------------------------------------------------------------------------------------------
-- FDL

local function add_address(tree, range, field, ext_field)
    local it = tree:add(field, range)
    it:add(ext_field, range)
    if range:uint() % 128 == 127 then it:append_text(" (broadcast)") end
    return range:uint() % 128, has(range:uint(), 0x80)
end

-- Address extension octets: DAE octets first, then SAE octets (protocol.md §A1.3).
local function decode_extensions(st, tree, c, present, ae_field, sap_field)
    if not present then return nil end
    local sap
    repeat
        local r = c:take(1, ae_field == F.dae and "DAE octet" or "SAE octet")
        local v = r:uint()
        local it = tree:add(ae_field, r)
        add_bits(it, r, { F.ae_more, F.ae_segment })
        if has(v, 0x40) then
            it:add(F.segment, r)
        else
            it:add(sap_field, r)
            if sap == nil then sap = v % 64 end
        end
    until not has(v, 0x80)
    return sap
end

local function request_expects_reply(fn)
    return fn == 0x3 or fn == 0x5 or fn == 0x7 or fn == 0x9 or fn == 0xC or fn == 0xD
        or fn == 0xE or fn == 0xF
end

local function link_response(st, tree, range)
    local pinfo = st.pinfo
    if not pinfo.visited then
        local p = state.pending
        state.pending = nil
        if p and (st.sd == 0xE5 or (st.da == p.sa and st.sa == p.da)) then
            state.response_to[pinfo.number] = p
            state.response_in[p.num] = pinfo.number
        end
    end
    local p = state.response_to[pinfo.number]
    if p then
        tree:add(F.response_to, range, p.num):set_generated()
        return p
    end
    return nil
end

local function dissect_fdl(st, tvb, root)
    local pinfo = st.pinfo
    local len = tvb:len()
    if len == 0 then
        malformed(st, root, "empty record")
        return
    end
    local sd = tvb(0, 1):uint()
    st.sd = sd
    root:add(F.sd, tvb(0, 1))
    local name = sd_names[sd]
    if name == nil then
        malformed(st, root, string.format("unknown start delimiter 0x%02X", sd))
        if len > 1 then root:add(F.data, tvb(1, len - 1)) end
        return
    end
    note(st, name)

    if sd == 0xE5 then
        local p = link_response(st, root, tvb(0, 1))
        note(st, p and string.format("ack to %s (frame %d)", p.service or "request", p.num)
            or "short acknowledgement")
        if len > 1 then
            root:add(F.trailing, tvb(1, len - 1))
            root:add_proto_expert_info(E.trailing, string.format("%d octet(s) after SC", len - 1))
        end
        return
    end

    if sd == 0xDC then
        if len < 3 then
            malformed(st, root, string.format("token truncated: %d of 3 octets", len))
            return
        end
        st.da = add_address(root, tvb(1, 1), F.da, F.da_ext)
        st.sa = add_address(root, tvb(2, 1), F.sa, F.sa_ext)
        root:add(F.service, tvb(0, 3), "Token"):set_generated()
        note(st, string.format("DA=%d SA=%d Token", st.da, st.sa))
        pinfo.cols.src:set(tostring(st.sa))
        pinfo.cols.dst:set(tostring(st.da))
        if not pinfo.visited then state.pending = nil end
        if len > 3 then
            root:add(F.trailing, tvb(3, len - 3))
            root:add_proto_expert_info(E.trailing, string.format("%d octet(s) after the token", len - 3))
        end
        return
    end

    -- SD1, SD2, SD3: where the header starts and how long the telegram must be.
    local hdr, total
    if sd == 0x10 then
        hdr, total = 1, 6
    elseif sd == 0xA2 then
        hdr, total = 1, 14
    else
        if len < 4 then
            if len >= 2 then root:add(F.le, tvb(1, 1)) end
            if len >= 3 then root:add(F.ler, tvb(2, 1)) end
            malformed(st, root, string.format("SD2 truncated: %d octets, header needs 4", len))
            return
        end
        local le, ler = tvb(1, 1):uint(), tvb(2, 1):uint()
        root:add(F.le, tvb(1, 1))
        local lit = root:add(F.ler, tvb(2, 1))
        local sit = root:add(F.sd_repeat, tvb(3, 1))
        if le ~= ler then
            malformed(st, lit, string.format("LE %d differs from LEr %d", le, ler))
            return
        end
        if tvb(3, 1):uint() ~= 0x68 then
            malformed(st, sit, string.format("repeated start delimiter is 0x%02X, not 0x68",
                tvb(3, 1):uint()))
            return
        end
        if le < 3 then
            malformed(st, lit, string.format("LE %d is too short for DA, SA and FC", le))
            return
        end
        if le < 4 or le > 249 then
            root:add_proto_expert_info(E.malformed, string.format("LE %d outside 4..249", le))
        end
        hdr, total = 4, le + 6
    end

    -- DA SA FC as far as they are present, so a truncated telegram still shows who sent it.
    if len > hdr then st.da, st.da_ext = add_address(root, tvb(hdr, 1), F.da, F.da_ext) end
    if len > hdr + 1 then st.sa, st.sa_ext = add_address(root, tvb(hdr + 1, 1), F.sa, F.sa_ext) end
    if st.da and st.sa then
        note(st, string.format("DA=%d SA=%d", st.da, st.sa))
        pinfo.cols.src:set(tostring(st.sa))
        pinfo.cols.dst:set(tostring(st.da))
    end
    if len < total then
        local fc_part = len > hdr + 2
        if fc_part then root:add(F.fc, tvb(hdr + 2, 1)) end
        malformed(st, root, string.format("%s truncated: %d of %d octets", name, len, total))
        if not pinfo.visited then state.pending = nil end
        return
    end

    local fcr = tvb(hdr + 2, 1)
    local fc = fcr:uint()
    local fit = root:add(F.fc, fcr)
    local is_request = has(fc, 0x40)
    local fn = bits(fc, 0, 4)
    fit:add(F.fc_reserved, fcr)
    fit:add(F.fc_request, fcr)
    if is_request then
        add_bits(fit, fcr, { F.fc_fcb, F.fc_fcv, F.fc_function })
        local fname = request_functions[fn] or string.format("reserved function %d", fn)
        fit:append_text(" (" .. fname .. ")")
        note(st, fname)
        if fn == 0x3 or fn == 0x5 or fn == 0xC or fn == 0xD or has(fc, 0x10) then
            note(st, string.format("FCB=%d FCV=%d", bits(fc, 5, 1), bits(fc, 4, 1)))
        end
    else
        add_bits(fit, fcr, { F.fc_station_type, F.fc_response })
        local st_type = bits(fc, 4, 2)
        local rname = response_short[fn] or string.format("reserved response %d", fn)
        fit:append_text(string.format(" (%s, %s)", rname, station_types[st_type]))
        note(st, st_type == 0 and rname or string.format("%s (%s)", rname, station_types[st_type]))
        if fn == 0x1 or fn == 0x2 or fn == 0x3 then
            fit:add_proto_expert_info(E.negative, "Negative response: " .. response_codes[fn])
        elseif fn == 0xA or fn == 0xD then
            fit:add_proto_expert_info(E.diag_pending)
        end
    end

    local du_start, du_end = hdr + 3, total - 2
    local fcs_r, ed_r = tvb(total - 2, 1), tvb(total - 1, 1)
    local sum = 0
    for i = hdr, du_end - 1 do sum = (sum + tvb(i, 1):uint()) % 256 end
    local fcs_ok = sum == fcs_r:uint()

    -- FCB repetition: same master, same slave, FCV=1 and the FCB it had last time. A telegram
    -- with a bad FCS never reached the station's FCB logic, so it does not count.
    if is_request and fcs_ok and (fn == 0xC or fn == 0xD or fn == 0x3 or fn == 0x5) then
        local key = st.sa .. ">" .. st.da
        if not pinfo.visited then
            if has(fc, 0x10) and state.fcb[key] == bits(fc, 5, 1) then
                state.repeat_[pinfo.number] = true
            end
            state.fcb[key] = bits(fc, 5, 1)
        end
        if state.repeat_[pinfo.number] then
            fit:add(F.fc_repeat, fcr, true):set_generated()
            fit:add_proto_expert_info(E.repeat_)
            note(st, "repeat")
        end
    end

    local paired
    if is_request then
        if not pinfo.visited then
            state.pending = nil
        end
        local rin = state.response_in[pinfo.number]
        if rin then root:add(F.response_in, fcr, rin):set_generated() end
    else
        paired = link_response(st, root, fcr)
    end

    local body = reader(tvb, du_start, du_end)
    local dsap, ssap, service
    local ok, err = pcall(function()
        dsap = decode_extensions(st, root, body, st.da_ext, F.dae, F.dsap)
        ssap = decode_extensions(st, root, body, st.sa_ext, F.sae, F.ssap)
    end)
    if not ok then
        if getmetatable(err) ~= Truncated then error(err, 0) end
        malformed(st, root, "address extension octets missing")
        dsap, ssap = nil, nil
    end
    if dsap or ssap then
        note(st, string.format("DSAP=%s SSAP=%s", dsap and tostring(dsap) or "-",
            ssap and tostring(ssap) or "-"))
    end
    if ok then
        if is_request then
            if dsap ~= nil then service = service_of_sap(dsap)
            elseif fn == 0x9 then service = "FDL_Status"
            elseif fn == 0xE then service = "Ident"
            elseif fn == 0xF then service = "LSAP_Status"
            elseif fn == 0x3 or fn == 0x4 or fn == 0x5 or fn == 0x6 or fn == 0xC or fn == 0xD then
                service = "Data_Exchange"
            end
        else
            if ssap ~= nil then service = service_of_sap(ssap)
            elseif paired and paired.service then service = paired.service
            elseif body:left() > 0 then service = "Data_Exchange"
            end
        end
        if service then
            root:add(F.service, fcr, service):set_generated()
            -- the function name ("FDL status") already says it
            if not (is_request and dsap == nil and (fn == 0x9 or fn == 0xE or fn == 0xF)) then
                note(st, service)
            end
        end
        if body:left() > 0 or service then
            root:add(F.du_len, tvb(du_start, math.max(du_end - du_start, 0)), body:left()):set_generated()
        end
        if du_end > du_start then root:add(F.du, tvb(du_start, du_end - du_start)) end
        local dok, derr = pcall(decode_service, st, root, body, service, is_request)
        if not dok then
            if getmetatable(derr) ~= Truncated then error(derr, 0) end
            malformed(st, root, string.format("%s truncated in %s (needs %d, %d left)",
                service or "data", derr.what, derr.need, derr.have))
        end
    end

    if is_request and request_expects_reply(fn) and not pinfo.visited then
        state.pending = { num = pinfo.number, da = st.da, sa = st.sa, service = service }
    end

    local fcs_it = root:add(F.fcs, fcs_r)
    fcs_it:add(F.fcs_ok, fcs_r, fcs_ok):set_generated()
    if not fcs_ok then
        fcs_it:add(F.fcs_computed, fcs_r, sum):set_generated()
        fcs_it:add_proto_expert_info(E.fcs, string.format("FCS 0x%02X, computed 0x%02X",
            fcs_r:uint(), sum))
        note(st, string.format("[FCS error: 0x%02X, computed 0x%02X]", fcs_r:uint(), sum))
    end
    local ed_it = root:add(F.ed, ed_r)
    if ed_r:uint() ~= 0x16 then
        malformed(st, ed_it, string.format("end delimiter 0x%02X, not 0x16", ed_r:uint()))
    end
    if len > total then
        root:add(F.trailing, tvb(total, len - total))
        root:add_proto_expert_info(E.trailing, string.format("%d octet(s) after the end delimiter",
            len - total))
    end
end

function proto.dissector(tvb, pinfo, tree)
    pinfo.cols.protocol:set("PROFIBUS")
    local st = { pinfo = pinfo, summary = {} }
    local root
    local ok, err = pcall(function()
        root = tree:add(proto, tvb:range(0, tvb:len()))
        dissect_fdl(st, tvb, root)
    end)
    if not ok then
        local where = root or tree
        where:add_proto_expert_info(E.internal, "Internal error in profibus.lua: " .. tostring(err))
        note(st, "[internal dissector error]")
    end
    local text = table.concat(st.summary, " ")
    if root then root:append_text(": " .. text) end
    pinfo.cols.info:set(text)
    return tvb:len()
end

DissectorTable.get("wtap_encap"):add(wtap.USER0, proto)
