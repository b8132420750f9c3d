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

-- The rest of the dissector lives in the parts beside this file, loaded from the folder this
-- file was loaded from (as movidrive_params.lua is): install all profibus*.lua files together.
local P = { proto = proto }
do
    local here = ""
    if debug and debug.getinfo then
        local src = (debug.getinfo(1, "S") or {}).source or ""
        here = src:match("^@(.*[/\\])") or ""
    end
    P.load_part = function(name)
        local ok, chunk, err = pcall(loadfile, here .. name)
        if not ok or type(chunk) ~= "function" then
            error("profibus.lua: cannot load " .. here .. name .. " (install it beside "
                .. "profibus.lua): " .. tostring(err or chunk), 0)
        end
        chunk(P)
    end
end
P.load_part("profibus_names.lua")
P.load_part("profibus_fields.lua")

------------------------------------------------------------------------------------------------
-- State across telegrams, built on the first pass and looked up by frame number afterwards
-- (Wireshark re-dissects frames in any order once they have been seen).

-- One table for the whole session: the parts hold it, so a new capture empties it in place.
local state = {}
local function reset_state()
    for k in pairs(state) do state[k] = nil end
    state.pending = nil           -- last request that expects an answer
    state.response_to = {}        -- response frame -> { num, service }
    state.response_in = {}        -- request frame -> response frame
    state.fcb = {}                -- "sa>da" -> last FCB of an FCV=1 request
    state.repeat_ = {}            -- frame -> true when FCB was unchanged
    state.channel = {}            -- slave address -> { present, frame } from Chk_Cfg
    state.channel_at = {}         -- Data_Exchange frame -> { present, frame } or false
end
reset_state()
function proto.init() reset_state() end
P.state = state

P.load_part("profibus_dpv0.lua")
P.load_part("profibus_dpv1.lua")

local bits, has, sd_names, request_functions = P.bits, P.has, P.sd_names, P.request_functions
local response_codes, response_short = P.response_codes, P.response_short
local station_types, service_of_sap, F, E = P.station_types, P.service_of_sap, P.F, P.E
local Truncated, reader, note, malformed = P.Truncated, P.reader, P.note, P.malformed
local add_bits, decode_cfg, decode_set_prm = P.add_bits, P.decode_cfg, P.decode_set_prm
local decode_slave_diag, decode_global_control = P.decode_slave_diag, P.decode_global_control
local decode_set_slave_add, cfg_has_channel = P.decode_set_slave_add, P.cfg_has_channel
local decode_data_exchange, decode_dpv1 = P.decode_data_exchange, P.decode_dpv1

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
