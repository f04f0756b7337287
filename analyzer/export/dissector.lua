-- The dissector body; the tables above it are generated from the protocol tables.

local bit = bit or bit32  -- Wireshark ships LuaBitOp as `bit` with every Lua version

local gimbal = Proto("gimbal", "Gimbal IDU protocol")
gimbal.prefs.port = Pref.uint("TCP port", DEFAULT_PORT, "TCP port of the IDU board (2000 by default)")

local pf = {
    header = ProtoField.uint16("gimbal.header", "Header", base.HEX),
    frame_type = ProtoField.uint8("gimbal.type", "Frame type", base.HEX, FRAME_TYPE_NAMES),
    reserved = ProtoField.bytes("gimbal.reserved", "Reserved"),
    can_id = ProtoField.uint32("gimbal.can_id", "CAN ID", base.HEX, CAN_ID_NAMES),
    marker = ProtoField.uint16("gimbal.marker", "Marker", base.HEX),
    can_data = ProtoField.bytes("gimbal.can_data", "CAN data"),
    s_id = ProtoField.uint8("gimbal.s_id", "S_ID", base.HEX, COMPONENT_NAMES),
    cmd = ProtoField.uint8("gimbal.cmd", "CMD", base.HEX),
    command = ProtoField.string("gimbal.command", "Command"),
    message = ProtoField.string("gimbal.message", "Message"),
    text = ProtoField.string("gimbal.text", "Text"),
    id_bytes = ProtoField.bytes("gimbal.feedback_id", "CMD+DID, C_ID, Data_id"),
    crc = ProtoField.uint16("gimbal.crc", "CRC", base.HEX),
    crc_status = ProtoField.uint8("gimbal.crc.status", "CRC status", base.DEC,
        {[0] = "Bad", [1] = "Good", [2] = "Not set (00 00)"}),
    crc_computed = ProtoField.uint16("gimbal.crc.computed", "CRC computed", base.HEX),
    padding = ProtoField.bytes("gimbal.padding", "Padding"),
    garbage = ProtoField.bytes("gimbal.garbage", "Bytes outside any frame"),
    direction = ProtoField.string("gimbal.direction", "Direction"),
}

local ex = {
    crc_bad = ProtoExpert.new("gimbal.crc.bad", "CRC mismatch", expert.group.CHECKSUM,
        expert.severity.ERROR),
    cut_short = ProtoExpert.new("gimbal.incomplete", "Frame cut short", expert.group.MALFORMED,
        expert.severity.ERROR),
    garbage = ProtoExpert.new("gimbal.garbage.expert", "Bytes outside any frame",
        expert.group.MALFORMED, expert.severity.WARN),
    doubt = ProtoExpert.new("gimbal.warning", "Doubt about a value or byte",
        expert.group.PROTOCOL, expert.severity.WARN),
    unknown = ProtoExpert.new("gimbal.unknown", "Unknown command or value",
        expert.group.UNDECODED, expert.severity.WARN),
}

-- One ProtoField per generated field spec (shared when several commands have the same).
local registered = {}
for _, spec in ipairs(FIELD_SPECS) do
    local abbr = spec.abbr
    if registered[abbr] == nil then
        local title = spec.name
        if spec.labels ~= nil then
            registered[abbr] = ProtoField.uint32(abbr, title, base.DEC, nil, nil, spec.desc)
        elseif spec.boolean then
            registered[abbr] = ProtoField.bool(abbr, title, base.NONE, nil, nil, spec.desc)
        elseif spec.div == 1 then
            if spec.signed then
                registered[abbr] = ProtoField.int32(abbr, title, base.DEC, nil, nil, spec.desc)
            else
                registered[abbr] = ProtoField.uint32(abbr, title, base.DEC, nil, nil, spec.desc)
            end
        else
            registered[abbr] = ProtoField.double(abbr, title, spec.desc)
        end
        pf[abbr] = registered[abbr]
    end
    spec.pf = registered[abbr]
end

local fields = {}
for _, field in pairs(pf) do
    fields[#fields + 1] = field
end
gimbal.fields = fields
gimbal.experts = {ex.crc_bad, ex.cut_short, ex.garbage, ex.doubt, ex.unknown}

-- CRC-16/MODBUS (the document's crc_fly16): reflected 0xA001, init 0xFFFF, low byte first.
local CRC_TABLE = {}
for i = 0, 255 do
    local crc = i
    for _ = 1, 8 do
        if bit.band(crc, 1) == 1 then
            crc = bit.bxor(bit.rshift(crc, 1), 0xA001)
        else
            crc = bit.rshift(crc, 1)
        end
    end
    CRC_TABLE[i] = crc
end

local function crc16(tvb, offset, length)
    local crc = 0xFFFF
    for i = offset, offset + length - 1 do
        local index = bit.band(bit.bxor(crc, tvb(i, 1):uint()), 0xFF)
        crc = bit.bxor(bit.rshift(crc, 8), CRC_TABLE[index])
    end
    return crc
end

local function fmt_number(spec, value)
    if spec.div == 1 then
        return string.format("%d", value)
    end
    return string.format("%." .. spec.decimals .. "f", value)
end

-- Add one field at tvb[base + spec.off]; returns its raw value and its text.
local function add_field(tree, tvb, base, spec)
    local range = tvb(base + spec.off, spec.size)
    local raw
    if spec.signed then raw = range:le_int() else raw = range:le_uint() end
    local text
    local item
    if spec.labels ~= nil then
        local label = spec.labels[raw] or spec.other_label
        if label == nil then
            label = string.format("unknown_0x%0" .. (2 * spec.size) .. "x", raw)
        end
        text = label
        item = tree:add(spec.pf, range, raw, string.format("%s: %s (%d)", spec.name, label, raw))
        if spec.labels[raw] == nil and spec.other_label == nil then
            item:add_proto_expert_info(ex.unknown,
                string.format("%s: unknown value %d (0x%02X)", spec.name, raw, raw))
        end
        return raw, text
    end
    if spec.boolean then
        text = tostring(raw ~= 0)
        item = tree:add(spec.pf, range, raw ~= 0, string.format("%s: %s", spec.name, text))
        if raw > 1 then
            item:add_proto_expert_info(ex.doubt,
                string.format("%s: flag value %d, expected 0 or 1", spec.name, raw))
        end
        return raw, text
    end
    local value = raw * spec.mul / spec.div
    if spec.div == 1 then value = raw * spec.mul end
    text = fmt_number(spec, value) .. spec.unit_suffix
    item = tree:add(spec.pf, range, value,
        string.format("%s: %s (raw %d)", spec.name, text, raw))
    if spec.expected ~= nil and raw ~= spec.expected then
        item:add_proto_expert_info(ex.doubt, string.format(
            "%s: raw value %d, the document prescribes %d", spec.name, raw, spec.expected))
    end
    if (spec.min ~= nil and raw < spec.min) or (spec.max ~= nil and raw > spec.max) then
        item:add_proto_expert_info(ex.doubt, string.format("%s: %s out of range [%s, %s]%s",
            spec.name, fmt_number(spec, value), spec.min_text, spec.max_text, spec.unit_suffix))
    elseif spec.soft_max ~= nil and raw > spec.soft_max then
        item:add_proto_expert_info(ex.doubt,
            string.format("%s: %s %s", spec.name, fmt_number(spec, value), spec.soft_note))
    end
    return raw, text
end

-- Adds the fields; returns their raw values by name.
local function add_fields(tree, tvb, base, specs, summary)
    local raws = {}
    for _, spec in ipairs(specs) do
        local raw, text = add_field(tree, tvb, base, spec)
        summary[#summary + 1] = spec.name .. "=" .. text
        raws[spec.name] = raw
    end
    return raws
end

local function hex(tvb, offset, count)
    local out = {}
    for i = 0, count - 1 do out[#out + 1] = string.format("%02X", tvb(offset + i, 1):uint()) end
    return table.concat(out, " ")
end

local function any_set(tvb, offset, count)
    for i = 0, count - 1 do
        if tvb(offset + i, 1):uint() ~= 0 then return true end
    end
    return false
end

-- Bytes that must be zero: one warning naming them when they are not.
local function check_zero(item, tvb, offset, count, what)
    if count > 0 and any_set(tvb, offset, count) then
        item:add_proto_expert_info(ex.doubt, what .. " are not zero: " .. hex(tvb, offset, count))
    end
end

-- The 8 CAN data bytes of a command at tvb[base]; returns a one-line summary.
local function dissect_command(tree, tvb, base)
    local s_id = tvb(base, 1):uint()
    local cmd = tvb(base + 1, 1):uint()
    local row = COMMANDS[s_id * 256 + cmd]
    local name = "unknown"
    if row ~= nil then name = row.name end
    local sub = tree:add(pf.command, tvb(base, 8), name)
    sub:add(pf.s_id, tvb(base, 1))
    sub:add(pf.cmd, tvb(base + 1, 1))
    if row == nil then
        sub:add_proto_expert_info(ex.unknown,
            string.format("unknown command S_ID 0x%02X CMD 0x%02X", s_id, cmd))
        return string.format("unknown command %02X %02X", s_id, cmd)
    end
    sub:append_text(" (" .. row.title .. ")")
    local summary = {}
    local used = {[0] = true, [1] = true}
    local fields = {}
    for _, spec in ipairs(row.params) do fields[#fields + 1] = spec end
    if row.selector ~= nil then
        local key = add_field(sub, tvb, base, row.selector)
        used[row.selector.off] = true
        summary[#summary + 1] = row.selector.name .. "=" ..
            (row.selector.labels[key] or tostring(key))
        local variant = row.variants[key]
        if variant ~= nil then
            for _, spec in ipairs(variant) do fields[#fields + 1] = spec end
        else
            sub:add_proto_expert_info(ex.doubt,
                string.format("%s: no layout for value %d", row.selector.name, key))
        end
    end
    add_fields(sub, tvb, base, fields, summary)
    for _, spec in ipairs(fields) do
        for i = spec.off, spec.off + spec.size - 1 do used[i] = true end
    end
    local unused = {}
    for i = 2, 7 do
        local byte = tvb(base + i, 1):uint()
        if not used[i] and byte ~= 0 then
            unused[#unused + 1] = string.format("DATA%d=0x%02X", i - 1, byte)
        end
    end
    if #unused > 0 then
        sub:add_proto_expert_info(ex.doubt, "bytes not used by " .. row.name ..
            " are not zero: " .. table.concat(unused, ", "))
    end
    if COMPONENT_NAMES[s_id] ~= "gimbal" then name = COMPONENT_NAMES[s_id] .. " " .. name end
    return name .. " " .. table.concat(summary, " ")
end

local function check_marker(tree, tvb, offset)
    local item = tree:add(pf.marker, tvb(offset + 12, 2))
    if tvb(offset + 12, 2):uint() ~= 0x4088 then
        item:add_proto_expert_info(ex.doubt, string.format("bytes 12-13 are %s, expected 40 88",
            hex(tvb, offset + 12, 2)))
    end
end

local function dissect_can_frame(tree, tvb, offset)
    local can_id = tvb(offset + 3, 4):uint()
    tree:add(pf.can_id, tvb(offset + 3, 4))
    check_zero(tree:add(pf.reserved, tvb(offset + 7, 5)), tvb, offset + 7, 5,
        "reserved bytes 7-11")
    check_marker(tree, tvb, offset)
    local data = offset + 14
    if can_id == CONTROL_ID then
        return dissect_command(tree, tvb, data)
    end
    local status = STATUS[can_id]
    if status ~= nil then
        local sub = tree:add(pf.message, tvb(data, 8), status.name)
        local summary = {}
        add_fields(sub, tvb, data, status.fields, summary)
        check_zero(sub, tvb, data + status.used, 8 - status.used,
            string.format("unused bytes %d-7", status.used))
        return status.name .. " " .. table.concat(summary, " ")
    end
    tree:add(pf.can_data, tvb(data, 8))
    if can_id == TEXT_ID or can_id == TEXT_END_ID then
        -- ASCII without the zero padding; anything else shown as \xHH
        local text = tvb(data, 8):raw():gsub("\0", ""):gsub("[^%g ]", function(c)
            return string.format("\\x%02X", c:byte())
        end)
        tree:add(pf.text, tvb(data, 8), text)
        return "text \"" .. text .. "\""
    end
    return string.format("CAN 0x%08X", can_id)
end

local function dissect_feedback(tree, tvb, offset, layout)
    check_zero(tree:add(pf.reserved, tvb(offset + 3, 9)), tvb, offset + 3, 9, "reserved bytes 3-11")
    local ids = tree:add(pf.id_bytes, tvb(offset + 12, 4))
    if hex(tvb, offset + 12, 4) ~= FEEDBACK_ID_BYTES then
        ids:add_proto_expert_info(ex.doubt, "bytes 12-15 are " .. hex(tvb, offset + 12, 4) ..
            ", expected " .. FEEDBACK_ID_BYTES)
    end
    local sub = tree:add(pf.message, tvb(offset + 16, layout.size - 18), layout.name)
    local summary = {}
    local raws = add_fields(sub, tvb, offset, layout.fields, summary)
    local motor = raws.motor_yaw_deg
    if motor ~= nil and math.abs(motor) > MOTOR_YAW_LIMIT
        and not WIDE_MOTOR_YAW_TYPES[raws.gimbal_type] then
        sub:add_proto_expert_info(ex.doubt, string.format(
            "motor_yaw_deg: %.2f deg out of range [%.2f, %.2f] deg for this gimbal type",
            motor / 100, -MOTOR_YAW_LIMIT / 100, MOTOR_YAW_LIMIT / 100))
    end
    return layout.name .. " " .. table.concat(summary, " ")
end

local function add_direction(tree, pinfo)
    if pinfo.dst_port == gimbal.prefs.port then
        tree:add(pf.direction, "gs_to_idu"):set_generated()
    else
        tree:add(pf.direction, "idu_to_gs"):set_generated()
    end
end

-- One frame of `size` bytes at `offset`, CRC already known; returns its summary.
local function dissect_frame(root, tvb, pinfo, offset, size, crc_state)
    local frame_type = tvb(offset + 2, 1):uint()
    local tree = root:add(gimbal, tvb(offset, size))
    tree:add(pf.header, tvb(offset, 2))
    tree:add(pf.frame_type, tvb(offset + 2, 1))
    add_direction(tree, pinfo)
    local summary
    if frame_type == FRAME_CONTROL then
        check_zero(tree:add(pf.reserved, tvb(offset + 3, 9)), tvb, offset + 3, 9,
            "reserved bytes 3-11")
        check_marker(tree, tvb, offset)
        summary = dissect_command(tree, tvb, offset + 14)
    elseif frame_type == FRAME_CAN then
        summary = dissect_can_frame(tree, tvb, offset)
    else
        summary = dissect_feedback(tree, tvb, offset, FEEDBACK[frame_type])
    end
    local crc_range = tvb(offset + size - 2, 2)
    local wire = crc_range:le_uint()
    local crc_item = tree:add_le(pf.crc, crc_range)
    local computed = crc16(tvb, offset, size - 2)
    tree:add(pf.crc_status, crc_range, crc_state):set_generated()
    if crc_state == 0 then
        tree:add(pf.crc_computed, crc_range, computed):set_generated()
        crc_item:add_proto_expert_info(ex.crc_bad, string.format(
            "type 0x%02X frame: CRC %02X %02X on the wire, %02X %02X computed", frame_type,
            bit.band(wire, 0xFF), bit.rshift(wire, 8), bit.band(computed, 0xFF),
            bit.rshift(computed, 8)))
        summary = "[CRC mismatch] " .. summary
    end
    tree:append_text(", " .. summary)
    return summary
end

local function find_header(tvb, from, to)
    for i = from, to - 2 do
        if tvb(i, 1):uint() == 0xEB and tvb(i + 1, 1):uint() == 0x90 then return i end
    end
    return nil
end

local function add_skipped(root, tvb, offset, count, infos)
    local item = root:add(gimbal, tvb(offset, count))
    item:add(pf.garbage, tvb(offset, count))
    item:append_text(string.format(", %d byte(s) outside any frame", count))
    item:add_proto_expert_info(ex.garbage,
        string.format("%d byte(s) outside any frame skipped", count))
    infos[#infos + 1] = string.format("[%d bytes skipped]", count)
end

-- Zero bytes after a feedback frame (up to 32 in all) are its padding.
local function zero_run(tvb, offset, limit)
    local n = 0
    while n < limit and offset + n < tvb:len() and tvb(offset + n, 1):uint() == 0 do
        n = n + 1
    end
    return n
end

-- Cut the bytes of one call into steps (frames, padding, skipped bytes, cut-short frames)
-- without showing anything yet; returns the steps and, when the last frame is not
-- complete, the offset where it starts (and how many bytes it lacks).
local function plan(tvb)
    local length = tvb:len()
    local offset = 0
    local steps = {}
    local function step(kind, at, count, extra)
        extra = extra or {}
        extra.kind, extra.at, extra.count = kind, at, count
        steps[#steps + 1] = extra
    end
    -- Leading zeros: the padding of a feedback frame that ended in the previous segment.
    local pad = zero_run(tvb, 0, FEEDBACK_SIZE - MIN_FEEDBACK_FRAME)
    if pad > 0 and (pad == length or find_header(tvb, pad, length) == pad) then
        step("padding", 0, pad)
        offset = pad
    end
    while offset < length do
        local start = find_header(tvb, offset, length)
        if start == nil then
            -- keep a last 0xEB: it may begin the next header
            local keep = 0
            if tvb(length - 1, 1):uint() == 0xEB then keep = 1 end
            if length - keep > offset then step("garbage", offset, length - keep - offset) end
            if keep == 1 then return steps, length - 1, DESEGMENT_ONE_MORE_SEGMENT end
            return steps
        end
        if start > offset then step("garbage", offset, start - offset) end
        offset = start
        if length - offset < 3 then return steps, offset, DESEGMENT_ONE_MORE_SEGMENT end
        local frame_type = tvb(offset + 2, 1):uint()
        local size = FRAME_SIZES[frame_type]
        if size == nil then
            step("garbage", offset, 2)
            offset = offset + 2
        elseif length - offset < size then
            return steps, offset, size - (length - offset)
        else
            local wire = tvb(offset + size - 2, 2):le_uint()
            local crc_state = 0
            if crc16(tvb, offset, size - 2) == wire then
                crc_state = 1
            elseif frame_type == FRAME_CAN and wire == 0
                and tvb(offset + 12, 2):uint() == 0x4088 then
                crc_state = 2
            end
            local restart = nil
            if crc_state == 0 then restart = find_header(tvb, offset + 1, offset + size) end
            if restart ~= nil then
                step("cut", offset, restart - offset, {frame_type = frame_type, size = size})
                offset = restart
            else
                step("frame", offset, size, {crc_state = crc_state})
                offset = offset + size
                if FEEDBACK[frame_type] ~= nil then
                    local n = zero_run(tvb, offset, FEEDBACK_SIZE - size)
                    if n > 0 then
                        step("padding", offset, n)
                        offset = offset + n
                    end
                end
            end
        end
    end
    return steps
end

local tcp_len = Field.new("tcp.len")

function gimbal.dissector(tvb, pinfo, root)
    local steps, wait_at = plan(tvb)
    if wait_at ~= nil then
        -- Always ask for whole segments: then the bytes TCP joined before this segment are
        -- exactly those before its payload. A frame starting among them cannot begin a new
        -- PDU (TCP would join all of it again): show nothing now, everything next time.
        local lengths = {tcp_len()}
        local earlier = 0
        if #lengths > 0 then earlier = tvb:len() - lengths[#lengths].value end
        if wait_at <= earlier then
            steps, wait_at = {}, 0
        end
        pinfo.desegment_offset = wait_at
        pinfo.desegment_len = DESEGMENT_ONE_MORE_SEGMENT
    end
    local infos = {}
    for _, step in ipairs(steps) do
        if step.kind == "padding" then
            root:add(gimbal, tvb(step.at, step.count)):add(pf.padding, tvb(step.at, step.count))
        elseif step.kind == "garbage" then
            add_skipped(root, tvb, step.at, step.count, infos)
        elseif step.kind == "cut" then
            local cut = root:add(gimbal, tvb(step.at, step.count))
            cut:append_text(string.format(", type 0x%02X frame cut short", step.frame_type))
            add_direction(cut, pinfo)
            cut:add_proto_expert_info(ex.cut_short, string.format(
                "type 0x%02X frame cut short after %d of %d bytes (a new header follows)",
                step.frame_type, step.count, step.size))
            infos[#infos + 1] = "[frame cut short]"
        else
            infos[#infos + 1] = dissect_frame(root, tvb, pinfo, step.at, step.count,
                step.crc_state)
        end
    end
    if #infos > 0 then
        -- a later PDU of the same packet: TCP fenced the column after the earlier one
        if tostring(pinfo.cols.protocol) == "GIMBAL" then
            pinfo.cols.info:append("; " .. table.concat(infos, "; "))
        else
            pinfo.cols.protocol = "GIMBAL"
            pinfo.cols.info = table.concat(infos, "; ")
        end
    end
    return tvb:len()
end

local registered_port = nil
local function register_port()
    local tcp = DissectorTable.get("tcp.port")
    if registered_port ~= nil then tcp:remove(registered_port, gimbal) end
    registered_port = gimbal.prefs.port
    tcp:add(registered_port, gimbal)
end

function gimbal.prefs_changed()
    if registered_port ~= gimbal.prefs.port then register_port() end
end

register_port()
