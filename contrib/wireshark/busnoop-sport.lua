-- busnoop-sport.lua: Wireshark dissector for FrSky S.Port frames exported by busnoop
-- (`busnoop sport SOURCE --export frames.pcapng`, link type USER0 = 147).
--
-- One packet is one frame as it was on the wire: 0x7E, the ID byte (physical ID in the low
-- 5 bits, check bits above), and for a sensor's answer the frame type, the app ID (16 bits,
-- little endian), the value (32 bits, little endian) and the CRC, byte-stuffed (0x7D x -> x^0x20).
-- Every sensor busnoop decodes is decoded the same way: the Sensor column's name (`sport.sensor`)
-- and each number the frame carries as busnoop's JSON `parts` name it (`sport.part`, EdgeTX's
-- names: VFAS, Cell1, RxBt, Lat), with its value as a number (`sport.value`, a double: filters
-- like `sport.value > 4` and `sport.part == "Cell1" && sport.value < 3.5` work) and unit
-- (`sport.unit`); what is text (GPS date and time, redundancy-box status, passthrough) is
-- `sport.text`. An app ID busnoop does not know carries its raw value, named by the app ID.
-- A bad CRC is expert info (error).
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
  number = ProtoField.none("sport.number", "Number"),
  part = ProtoField.string("sport.part", "Name"),
  value = ProtoField.double("sport.value", "Value"),
  unit = ProtoField.string("sport.unit", "Unit"),
  text = ProtoField.string("sport.text", "Text"),
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

-- EdgeTX's names in its logs where busnoop's Sensor column follows the S-Port_Snoop sample.
local log_names = { Vario = "VSpd", Amps = "Curr", Volts = "VFAS" }

-- Two 16-bit halves feeding two sensors: label, {name, unit, decimals} x2, signed, multiplier
-- of the first half.
local pairs16 = {
  [0x0730] = { "Roll/Ptch", { "Roll", "deg", 2 }, { "Ptch", "deg", 2 }, true, 1 },
  [0x0B00] = { "RB1V/RB1A", { "RB1V", "V", 3 }, { "RB1A", "A", 2 }, false, 1 },
  [0x0B10] = { "RB2V/RB2A", { "RB2V", "V", 3 }, { "RB2A", "A", 2 }, false, 1 },
  [0x0B30] = { "RB1C/RB2C", { "RB1C", "mAh", 0 }, { "RB2C", "mAh", 0 }, false, 1 },
  [0x0B50] = { "EscV/EscA", { "EscV", "V", 2 }, { "EscA", "A", 2 }, false, 1 },
  [0x0B60] = { "Erpm/EscC", { "Erpm", "rpm", 0 }, { "EscC", "mAh", 0 }, false, 100 },
  [0x0B90] = { "CH1A/CH2A", { "CH1A", "A", 2 }, { "CH2A", "A", 2 }, false, 1 },
  [0x0BA0] = { "CH3A/CH4A", { "CH3A", "A", 2 }, { "CH4A", "A", 2 }, false, 1 },
  [0x0BB0] = { "CH5A/CH6A", { "CH5A", "A", 2 }, { "CH6A", "A", 2 }, false, 1 },
  [0x0BC0] = { "CH7A/CH8A", { "CH7A", "A", 2 }, { "CH8A", "A", 2 }, false, 1 },
  [0x0E50] = { "BecV/BecA", { "BecV", "V", 3 }, { "BecA", "A", 3 }, false, 1 },
}

-- Legacy FrSky D hub IDs (app IDs 0x0000-0x00FF).
local hub_names = {
  [0x01] = "GPS_ALT_BP", [0x02] = "TEMP1", [0x03] = "RPM", [0x04] = "FUEL", [0x05] = "TEMP2",
  [0x06] = "VOLTS", [0x09] = "GPS_ALT_AP", [0x10] = "BARO_ALT_BP", [0x11] = "GPS_SPEED_BP",
  [0x12] = "GPS_LONG_BP", [0x13] = "GPS_LAT_BP", [0x14] = "GPS_COURS_BP",
  [0x15] = "GPS_DAY_MONTH", [0x16] = "GPS_YEAR", [0x17] = "GPS_HOUR_MIN", [0x18] = "GPS_SEC",
  [0x19] = "GPS_SPEED_AP", [0x1A] = "GPS_LONG_AP", [0x1B] = "GPS_LAT_AP",
  [0x1C] = "GPS_COURS_AP", [0x21] = "BARO_ALT_AP", [0x22] = "GPS_LONG_EW",
  [0x23] = "GPS_LAT_NS", [0x24] = "ACCEL_X", [0x25] = "ACCEL_Y", [0x26] = "ACCEL_Z",
  [0x28] = "CURRENT", [0x30] = "VARIO", [0x39] = "VFAS", [0x3A] = "VOLTS_BP",
  [0x3B] = "VOLTS_AP",
}

local r9_mw = { [0] = 1, [5] = 3, [10] = 10, [13] = 20, [14] = 25, [20] = 100, [23] = 200,
  [27] = 500, [30] = 1000 }

local function band(a, b) return bit32.band(a, b) end
local function rshift(a, n) return bit32.rshift(a, n) end
local function signed16(h) if h >= 0x8000 then return h - 0x10000 end return h end

-- The sensor's name, its numbers ({name, integer, decimals, unit} each) and its text, as
-- busnoop's table has them (src/sport/values.rs).
local function decode(app, phys, raw)
  local base = band(app, 0xFFF0)
  local s = scalars[base]
  if s then
    local n = raw
    if s[4] and n >= 0x80000000 then n = n - 0x100000000 end
    local prec = s[3]
    -- The flight-controller slot (physical ID 0x1B) sends acceleration in 0.01 g.
    if base >= 0x0700 and base <= 0x0720 and phys == 0x1B then prec = 2 end
    return s[1], { { log_names[s[1]] or s[1], n, prec, s[2] } }
  end
  local pr = pairs16[base]
  if pr then
    local lo, hi = band(raw, 0xFFFF), rshift(raw, 16)
    if pr[4] then lo, hi = signed16(lo), signed16(hi) end
    lo = lo * pr[5]
    return pr[1], { { pr[2][1], lo, pr[2][3], pr[2][2] }, { pr[3][1], hi, pr[3][3], pr[3][2] } }
  end
  if app <= 0x00FF then
    if app == 0x06 then
      local lo, hi = band(raw, 0xFF), band(rshift(raw, 8), 0xFF)
      local idx = rshift(lo, 4)
      local v = bit32.bor(bit32.lshift(band(lo, 0x0F), 8), hi)
      return "Hub Cell", { { "Cell" .. (idx + 1), v * 2, 3, "V" } }
    end
    local name = hub_names[app] or string.format("0x%02X", app)
    return "Hub " .. name, { { name, band(raw, 0xFFFF), 0, "" } }
  end
  if app >= 0x0300 and app <= 0x030F then
    local index, count = band(raw, 0x0F), band(rshift(raw, 4), 0x0F)
    local c0, c1 = band(rshift(raw, 8), 0x0FFF), band(rshift(raw, 20), 0x0FFF)
    local nums = { { "Cell" .. (band(index, 0x0F) + 1), c0 * 2, 3, "V" } }
    if index + 1 < count then
      table.insert(nums, { "Cell" .. (band(index + 1, 0x0F) + 1), c1 * 2, 3, "V" })
    end
    return "Cels", nums
  end
  if app >= 0x0800 and app <= 0x080F then
    local lon, neg = band(raw, 0x80000000) ~= 0, band(raw, 0x40000000) ~= 0
    -- 1/10000 minute to 1e-7 degree, rounded half up: raw * 100 / 6.
    local e7 = math.floor((band(raw, 0x3FFFFFFF) * 100 + 3) / 6)
    if neg then e7 = -e7 end
    return "GPS", { { lon and "Lon" or "Lat", e7, 7, "deg" } }
  end
  if app >= 0x0850 and app <= 0x085F then
    local b0, b1, b2, b3 = band(raw, 0xFF), band(rshift(raw, 8), 0xFF),
      band(rshift(raw, 16), 0xFF), rshift(raw, 24)
    if b0 ~= 0 then
      return "Date", {}, string.format("%d-%02d-%02d", 2000 + b3, b2, b1)
    end
    return "Time", {}, string.format("%02d:%02d:%02d", b3, b2, b1)
  end
  if app >= 0x0B20 and app <= 0x0B2F then return "RBCS/RBS", {}, nil end
  if app >= 0x0B70 and app <= 0x0B7F then
    return "EscT", { { "EscT", band(raw, 0xFF), 0, "degC" } }
  end
  if app >= 0x0B80 and app <= 0x0B8F then return "RBES", {}, nil end
  if app >= 0x5000 and app <= 0x50FF then return string.format("0x%04X", app), {}, nil end
  if app >= 0x6800 and app <= 0x680F then
    local a, v, t = band(raw, 0xFF), band(rshift(raw, 8), 0xFF), band(rshift(raw, 16), 0xFF)
    return "Servo", { { "SrvA", a, 1, "A" }, { "SrvV", v, 1, "V" }, { "SrvT", t, 0, "degC" } },
      rshift(raw, 24) == 0 and "SrvS=OK" or "SrvS=STALL"
  end
  if app == 0xF010 then return "VFR", { { "VFR", 100 - band(raw, 0xFF), 0, "%" } } end
  if app == 0xF101 then return "RSSI", { { "RSSI", band(raw, 0xFF), 0, "dB" } } end
  if app >= 0xF102 and app <= 0xF104 then
    local name = ({ [0xF102] = "A1", [0xF103] = "A2", [0xF104] = "RxBt" })[app]
    -- Hundredths of a volt: raw * 1320 / 255, rounded half up.
    local cv = math.floor((band(raw, 0xFF) * 1320 * 2 + 255) / (2 * 255))
    return name, { { name, cv, 2, "V" } }
  end
  if app == 0xF105 then return "SWR", { { "SWR", band(raw, 0xFF), 0, "" } } end
  if app == 0xF106 then
    return "XJT version", { { "XJT version", band(raw, 0xFFFF), 0, "" } }
  end
  if app == 0xF107 then
    local dbm = band(raw, 0xFF)
    local mw = r9_mw[dbm]
    if mw then return "R9PW", { { "R9PW", mw, 0, "mW" } } end
    return "R9PW", {}, "dBm=" .. dbm
  end
  local hex = string.format("0x%04X", app)
  return hex, { { hex, raw, 0, "" } }
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
  if ftype == 0x10 and crc_ok then
    local name, nums, text = decode(app, phys, raw)
    t:add(pf.sensor, name)
    local shown = {}
    for _, n in ipairs(nums) do
      local part, int, prec, unit = n[1], n[2], n[3], n[4]
      local written = fixed(int, prec)
      local sub = t:add(pf.number, u(5, 4))
      sub:set_text(string.format("%s = %s %s", part, written, unit))
      sub:add(pf.part, part)
      sub:add(pf.value, int / (10 ^ prec))
      sub:add(pf.unit, unit)
      table.insert(shown, string.format("%s=%s%s", part, written, unit))
    end
    if text then
      t:add(pf.text, text)
      table.insert(shown, text)
    end
    info = string.format("ID %d %s %s", phys, name, table.concat(shown, " "))
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
