-- busnoop-sab.lua: Wireshark dissector for modm SAB / SAB2 frames exported by busnoop
-- (`busnoop sab2 SOURCE --export frames.pcapng`, link type USER1 = 148).
--
-- One packet is one frame as it was on the wire, in either framing:
--   SAB v1: 54 LENGTH HEADER COMMAND DATA[LENGTH] CRC8   (CRC-8/MAXIM-DOW over LENGTH..DATA)
--   SAB2:   7E HEADER COMMAND DATA CRClo CRChi 7E        (7D x -> x^0x20; CRC-16/MODBUS over
--                                                         HEADER..DATA)
-- HEADER: bits 7..6 flags (00 request, 01 reserved, 10 NACK, 11 ACK), bits 5..0 the address.
-- A bad CRC is expert info (error). Other bytes busnoop exported (garbage, runts) are shown as
-- such. A valid request's or ACK's payload of 1, 2 or 4 bytes is a number, as busnoop's default
-- rule reads it (an unsigned little-endian integer, docs/sab.md "Values"): `sab.value` (a number:
-- `sab.value > 1000` filters), named as busnoop's `parts` name it (`sab.value_name`: the command
-- `0x10`, a request's `0x10.req`). Types declared with busnoop's `--value` are busnoop's alone.
--
-- Install: copy or link into your personal Lua plugins folder (Help > About Wireshark >
-- Folders), or load it once: wireshark -X lua_script:busnoop-sab.lua frames.pcapng
-- See docs/wireshark.md in busnoop. License: as busnoop (MIT OR Apache-2.0).

local p = Proto("busnoop_sab", "modm SAB (busnoop)")

local flag_names = { [0] = "Request", [1] = "Reserved", [2] = "NACK", [3] = "ACK" }

local pf = {
  framing = ProtoField.string("sab.framing", "Framing"),
  length = ProtoField.uint8("sab.length", "Length", base.DEC),
  header = ProtoField.uint8("sab.header", "Header", base.HEX),
  flags = ProtoField.uint8("sab.flags", "Flags", base.DEC, flag_names, 0xC0),
  address = ProtoField.uint8("sab.address", "Address", base.DEC, nil, 0x3F),
  type_name = ProtoField.string("sab.type", "Type"),
  command = ProtoField.uint8("sab.command", "Command", base.HEX),
  payload = ProtoField.bytes("sab.payload", "Payload"),
  error_code = ProtoField.uint8("sab.error", "NACK error code", base.HEX),
  crc8 = ProtoField.uint8("sab.crc8", "CRC-8", base.HEX),
  crc16 = ProtoField.uint16("sab.crc16", "CRC-16", base.HEX),
  crc_status = ProtoField.string("sab.crc_status", "CRC status"),
  value_name = ProtoField.string("sab.value_name", "Value name"),
  value = ProtoField.uint32("sab.value", "Value", base.DEC),
}
p.fields = pf

local ef_crc = ProtoExpert.new("sab.crc.bad", "Bad CRC", expert.group.CHECKSUM,
  expert.severity.ERROR)
local ef_short = ProtoExpert.new("sab.short", "Not a whole SAB frame", expert.group.MALFORMED,
  expert.severity.ERROR)
p.experts = { ef_crc, ef_short }

-- A reflected CRC over bytes `from`..`to` of `tvb`: CRC-8/MAXIM-DOW is (0x00, 0x8C),
-- CRC-16/MODBUS is (0xFFFF, 0xA001).
local function crc_reflected(tvb, from, to, init, poly)
  local crc = init
  for i = from, to do
    crc = bit32.bxor(crc, tvb(i, 1):uint())
    for _ = 1, 8 do
      if bit32.band(crc, 1) == 1 then
        crc = bit32.bxor(bit32.rshift(crc, 1), poly)
      else
        crc = bit32.rshift(crc, 1)
      end
    end
  end
  return crc
end

local function crc8_maxim(tvb, from, to)
  return crc_reflected(tvb, from, to, 0x00, 0x8C)
end

local function crc16_modbus(tvb, from, to)
  return crc_reflected(tvb, from, to, 0xFFFF, 0xA001)
end

-- HEADER and COMMAND at `at` of `u`, payload of `n` bytes after them.
local function body(u, at, n, t, pinfo)
  local h = u(at, 1):uint()
  local flags = bit32.rshift(h, 6)
  local addr = bit32.band(h, 0x3F)
  t:add(pf.header, u(at, 1))
  t:add(pf.flags, u(at, 1))
  t:add(pf.address, u(at, 1))
  t:add(pf.type_name, flag_names[flags])
  t:add(pf.command, u(at + 1, 1))
  if n > 0 then
    t:add(pf.payload, u(at + 2, n))
    if flags == 2 and n == 1 then t:add(pf.error_code, u(at + 2, 1)) end
  end
  local info = string.format("%s address %d command 0x%02X%s", flag_names[flags], addr,
    u(at + 1, 1):uint(), n > 0 and string.format(" (%d bytes)", n) or "")
  -- The number of a request's or an ACK's payload of 1, 2 or 4 bytes, once its CRC is known.
  local number = nil
  if (flags == 0 or flags == 3) and (n == 1 or n == 2 or n == 4) then
    local name = string.format("0x%02X", u(at + 1, 1):uint())
    if flags == 0 then name = name .. ".req" end
    number = { name = name, range = u(at + 2, n) }
  end
  return info, number
end

-- Adds the payload's number to the tree and the info line.
local function add_number(t, number, info)
  if number == nil then return info end
  local v = number.range:le_uint()
  t:add(pf.value_name, number.name)
  t:add_le(pf.value, number.range)
  return string.format("%s %s=%d", info, number.name, v)
end

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  if len < 1 then return 0 end
  pinfo.cols.protocol = "SAB"
  local t = tree:add(p, tvb(), "modm SAB")
  local first = tvb(0, 1):uint()
  local info
  local ok
  if first == 0x54 and len >= 5 then
    t:add(pf.framing, "SAB v1 (0x54, CRC-8)")
    local n = tvb(1, 1):uint()
    t:add(pf.length, tvb(1, 1))
    if len < n + 5 then
      t:add_proto_expert_info(ef_short)
      pinfo.cols.info = "SAB v1 frame cut short"
      return len
    end
    local number
    info, number = body(tvb, 2, n, t, pinfo)
    ok = crc8_maxim(tvb, 1, n + 3) == tvb(n + 4, 1):uint()
    if ok then info = add_number(t, number, info) end
    local c = t:add(pf.crc8, tvb(n + 4, 1))
    if not ok then c:add_proto_expert_info(ef_crc) end
  elseif first == 0x7E then
    t:add(pf.framing, "SAB2 (0x7E, CRC-16)")
    -- Unescape the bytes between the flags.
    local ba = ByteArray.new()
    local stuffed = false
    local i = 1
    while i < len do
      local b = tvb(i, 1):uint()
      if b == 0x7E then break end
      if b == 0x7D and i + 1 < len then
        b = bit32.bxor(tvb(i + 1, 1):uint(), 0x20)
        stuffed = true
        i = i + 1
      end
      ba:append(ByteArray.new(string.format("%02x", b)))
      i = i + 1
    end
    local u = tvb(1)
    if stuffed then u = ba:tvb("Unescaped SAB2 frame") end
    local n = ba:len()
    if n < 4 then
      t:add_proto_expert_info(ef_short)
      pinfo.cols.info = string.format("SAB2 runt (%d bytes between flags)", n)
      return len
    end
    local number
    info, number = body(u, 0, n - 4, t, pinfo)
    ok = crc16_modbus(u, 0, n - 3) == u(n - 2, 2):le_uint()
    if ok then info = add_number(t, number, info) end
    local c = t:add_le(pf.crc16, u(n - 2, 2))
    if not ok then c:add_proto_expert_info(ef_crc) end
  else
    t:add_proto_expert_info(ef_short)
    pinfo.cols.info = string.format("%d bytes that are no SAB frame", len)
    return len
  end
  t:add(pf.crc_status, ok and "good" or "bad")
  if not ok then info = info .. " [bad CRC]" end
  pinfo.cols.info = info
  return len
end

DissectorTable.get("wtap_encap"):add((wtap_encaps or wtap).USER1, p)
