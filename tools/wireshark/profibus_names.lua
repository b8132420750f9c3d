-- profibus.lua, part: value names and the texts built from them (FDL, DP-V0, MOVILINK, DP-V1, data set 47,
-- I&M).
-- Loaded by profibus.lua with its shared table P (the names the parts give each other);
-- when Wireshark runs this file as a plugin of its own, it does nothing.
local P = ...
if type(P) ~= "table" then return end

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

-- For the other parts.
P.bits = bits
P.has = has
P.sd_names = sd_names
P.request_functions = request_functions
P.response_codes = response_codes
P.response_short = response_short
P.station_types = station_types
P.service_of_sap = service_of_sap
P.cfg_directions = cfg_directions
P.cfg_special = cfg_special
P.alarm_modes = alarm_modes
P.ext_diag_types = ext_diag_types
P.ml_services = ml_services
P.ml_param_names = ml_param_names
P.ml_index_text = ml_index_text
P.ml_lengths = ml_lengths
P.ml_error_classes = ml_error_classes
P.ml_class8_codes = ml_class8_codes
P.movilink_error_text = movilink_error_text
P.dpv1_functions = dpv1_functions
P.dpv1_error_decodes = dpv1_error_decodes
P.dpv1_error_classes = dpv1_error_classes
P.dpv1_error_text = dpv1_error_text
P.abort_subnets = abort_subnets
P.abort_instances = abort_instances
P.abort_reasons = abort_reasons
P.ds47_ids = ds47_ids
P.ds47_formats = ds47_formats
P.ds47_format_sizes = ds47_format_sizes
P.profidrive_attributes = profidrive_attributes
P.movilink_attributes = movilink_attributes
P.profidrive_error_text = profidrive_error_text
P.im_records = im_records
