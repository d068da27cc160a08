-- busnoop-sport.lua: Wireshark dissector for FrSky S.Port frames exported by busnoop
-- (`busnoop sport SOURCE --export frames.pcapng`, link type USER0 = 147).
--
-- One packet is one frame as it was on the wire: 0x7E, the ID byte (physical ID in the low
-- 5 bits, check bits above), and for a sensor's answer the frame type, the app ID (16 bits,
-- little endian), the value (32 bits, little endian) and the CRC, byte-stuffed (0x7D x -> x^0x20).
-- Values are scaled and named as busnoop's table names them (scalar sensors and 16-bit pairs);
-- other app IDs show their raw value. A bad CRC is expert info (error).
--
-- Install: copy or link into your personal Lua plugins folder (Help > About Wireshark >
-- Folders), or load it once: wireshark -X lua_script:busnoop-sport.lua frames.pcapng
-- See docs/wireshark.md in busnoop. License: as busnoop (MIT OR Apache-2.0).

local p = Proto("busnoop_sport", "FrSky S.Port (busnoop)")

local frame_types = {
  [0x00] = "Null", [0x10] = "Data", [0x30] = "Read", [0x31] = "Write", [0x32] = "Response",
}

local pf = {
  header = ProtoField.uint8("sport.header", "Header", base.HEX),
  id_byte = ProtoField.uint8("sport.id_byte", "ID byte", base.HEX),
  phys_id = ProtoField.uint8("sport.phys_id", "Physical ID", base.DEC),
  poll = ProtoField.bool("sport.poll", "Poll (no answer in this frame)"),
  frame_type = ProtoField.uint8("sport.frame_type", "Frame type", base.HEX, frame_types),
  type_name = ProtoField.string("sport.type", "Type"),
  app_id = ProtoField.uint16("sport.app_id", "App ID", base.HEX),
  sensor = ProtoField.string("sport.sensor", "Sensor"),
  raw_value = ProtoField.uint32("sport.raw_value", "Raw value", base.DEC_HEX),
  value = ProtoField.string("sport.value", "Value"),
  unit = ProtoField.string("sport.unit", "Unit"),
  crc = ProtoField.uint8("sport.crc", "CRC", base.HEX),
  crc_status = ProtoField.string("sport.crc_status", "CRC status"),
  stuffed = ProtoField.uint8("sport.stuffed", "Stuffed bytes", base.DEC),
}
p.fields = pf

local ef_crc = ProtoExpert.new("sport.crc.bad", "Bad CRC", expert.group.CHECKSUM,
  expert.severity.ERROR)
local ef_short = ProtoExpert.new("sport.short", "Frame cut short", expert.group.MALFORMED,
  expert.severity.ERROR)
p.experts = { ef_crc, ef_short }

-- Scalar sensors by app ID with the instance nibble cleared: name, unit, decimals, signed.
local scalars = {
  [0x0100] = { "Alt", "m", 2, true }, [0x0110] = { "Vario", "m/s", 2, true },
  [0x0200] = { "Amps", "A", 1, false }, [0x0210] = { "Volts", "V", 2, false },
  [0x0400] = { "Tmp1", "degC", 0, true }, [0x0410] = { "Tmp2", "degC", 0, true },
  [0x0500] = { "RPM", "rpm", 0, false }, [0x0600] = { "Fuel", "%", 0, false },
  [0x0700] = { "AccX", "g", 3, true }, [0x0710] = { "AccY", "g", 3, true },
  [0x0720] = { "AccZ", "g", 3, true }, [0x0820] = { "GAlt", "m", 2, true },
  [0x0830] = { "GSpd", "kts", 3, false }, [0x0840] = { "Hdg", "deg", 2, false },
  [0x0900] = { "A3", "V", 2, true }, [0x0910] = { "A4", "V", 2, true },
  [0x0A00] = { "ASpd", "kts", 1, false }, [0x0A10] = { "Fuel", "ml", 2, false },
  [0x0B40] = { "Chan", "", 0, false }, [0x0D00] = { "GTp1", "degC", 0, true },
  [0x0D10] = { "GTp2", "degC", 0, true }, [0x0D20] = { "GRPM", "rpm", 0, false },
  [0x0D30] = { "GRVl", "ml", 0, false }, [0x0D40] = { "GRPc", "%", 0, false },
  [0x0D50] = { "GFlo", "ml/min", 0, false }, [0x0D60] = { "GMFl", "ml/min", 0, false },
  [0x0D70] = { "GAFl", "ml/min", 0, false },
}

-- Fixed-point text of an integer with `prec` decimals (exact, no floating point rounding).
local function fixed(n, prec)
  local neg = n < 0
  if neg then n = -n end
  local s
  if prec == 0 then
    s = string.format("%d", n)
  else
    local scale = 10 ^ prec
    s = string.format("%d.%0" .. prec .. "d", math.floor(n / scale), n % scale)
  end
  if neg then s = "-" .. s end
  return s
end

local function value_of(app_id, phys, raw)
  local s = scalars[bit32.band(app_id, 0xFFF0)]
  if s == nil then return nil end
  local n = raw
  if s[4] and n >= 0x80000000 then n = n - 0x100000000 end
  local prec = s[3]
  -- The flight-controller slot (physical ID 0x1B) sends acceleration in 0.01 g.
  if s[2] == "g" and phys == 0x1B then prec = 2 end
  return s[1], fixed(n, prec), s[2]
end

function p.dissector(tvb, pinfo, tree)
  if tvb:len() < 1 then return 0 end
  pinfo.cols.protocol = "S.Port"
  local t = tree:add(p, tvb(), "FrSky S.Port")
  -- Undo the byte stuffing.
  local ba = ByteArray.new()
  ba:set_size(0)
  local stuffed = 0
  local i = 0
  while i < tvb:len() do
    local b = tvb(i, 1):uint()
    if b == 0x7D and i > 0 and i + 1 < tvb:len() then
      b = bit32.bxor(tvb(i + 1, 1):uint(), 0x20)
      stuffed = stuffed + 1
      i = i + 1
    end
    ba:append(ByteArray.new(string.format("%02x", b)))
    i = i + 1
  end
  local u = tvb
  if stuffed > 0 then
    u = ba:tvb("Unstuffed S.Port frame")
    t:add(pf.stuffed, stuffed)
  end
  t:add(pf.header, u(0, 1))
  if u:len() < 2 then
    t:add_proto_expert_info(ef_short)
    return tvb:len()
  end
  local id = u(1, 1):uint()
  local phys = bit32.band(id, 0x1F)
  t:add(pf.id_byte, u(1, 1))
  t:add(pf.phys_id, u(1, 1), phys)
  if u:len() == 2 then
    t:add(pf.poll, true)
    pinfo.cols.info = string.format("Poll ID %d", phys)
    return tvb:len()
  end
  if u:len() < 10 then
    t:add_proto_expert_info(ef_short)
    pinfo.cols.info = string.format("ID %d: frame cut short (%d bytes)", phys, u:len())
    return tvb:len()
  end
  local ftype = u(2, 1):uint()
  local app = u(3, 2):le_uint()
  local raw = u(5, 4):le_uint()
  local sum = 0
  for k = 2, 9 do
    sum = sum + u(k, 1):uint()
    sum = bit32.band(sum, 0xFF) + bit32.rshift(sum, 8)
  end
  local crc_ok = sum == 0xFF
  t:add(pf.frame_type, u(2, 1))
  local tname = frame_types[ftype] or string.format("0x%02X", ftype)
  t:add(pf.type_name, tname)
  t:add_le(pf.app_id, u(3, 2))
  t:add_le(pf.raw_value, u(5, 4))
  local info = string.format("ID %d %s app 0x%04X", phys, tname, app)
  if ftype == 0x10 then
    local name, text, unit = value_of(app, phys, raw)
    if name then
      t:add(pf.sensor, name)
      t:add(pf.value, u(5, 4), text)
      t:add(pf.unit, unit)
      info = string.format("ID %d %s = %s %s", phys, name, text, unit)
    end
  end
  local c = t:add(pf.crc, u(9, 1))
  t:add(pf.crc_status, crc_ok and "good" or "bad")
  if not crc_ok then
    c:add_proto_expert_info(ef_crc)
    info = info .. " [bad CRC]"
  end
  pinfo.cols.info = info
  return tvb:len()
end

DissectorTable.get("wtap_encap"):add((wtap_encaps or wtap).USER0, p)
