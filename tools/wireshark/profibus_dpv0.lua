-- profibus.lua, part: bounded reading of a telegram and the DP-V0 services (Set_Prm, Chk_Cfg,
-- Slave_Diag, Global_Control, Set_Slave_Add, Data_Exchange with the MOVILINK channel).
-- Loaded by profibus.lua with its shared table P (the names the parts give each other);
-- when Wireshark runs this file as a plugin of its own, it does nothing.
local P = ...
if type(P) ~= "table" then return end

local proto, bits, has, cfg_directions = P.proto, P.bits, P.has, P.cfg_directions
local cfg_special, ext_diag_types, ml_services = P.cfg_special, P.ext_diag_types, P.ml_services
local ml_param_names, ml_index_text = P.ml_param_names, P.ml_index_text
local ml_class8_codes, F, E, state = P.ml_class8_codes, P.F, P.E, P.state

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

-- For the other parts.
P.Truncated = Truncated
P.reader = reader
P.note = note
P.malformed = malformed
P.add_bits = add_bits
P.decode_cfg = decode_cfg
P.decode_set_prm = decode_set_prm
P.decode_slave_diag = decode_slave_diag
P.decode_global_control = decode_global_control
P.decode_set_slave_add = decode_set_slave_add
P.cfg_has_channel = cfg_has_channel
P.decode_data_exchange = decode_data_exchange
