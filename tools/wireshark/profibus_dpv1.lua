-- profibus.lua, part: DP-V1 PDUs (MSAC1, MSAC2), data set 47 and I&M.
-- Loaded by profibus.lua with its shared table P (the names the parts give each other);
-- when Wireshark runs this file as a plugin of its own, it does nothing.
local P = ...
if type(P) ~= "table" then return end

local proto, bits, has, ml_param_names = P.proto, P.bits, P.has, P.ml_param_names
local ml_index_text, movilink_error_text = P.ml_index_text, P.movilink_error_text
local dpv1_functions, dpv1_error_text = P.dpv1_functions, P.dpv1_error_text
local abort_instances, abort_reasons, ds47_ids = P.abort_instances, P.abort_reasons, P.ds47_ids
local ds47_format_sizes, profidrive_attributes = P.ds47_format_sizes, P.profidrive_attributes
local movilink_attributes, profidrive_error_text = P.movilink_attributes, P.profidrive_error_text
local im_records, F, E, reader, note = P.im_records, P.F, P.E, P.reader, P.note
local malformed, add_bits = P.malformed, P.add_bits

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

-- For the other parts.
P.decode_dpv1 = decode_dpv1
