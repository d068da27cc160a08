-- busnoop-crsf.lua: Wireshark dissector for CRSF (TBS Crossfire, ExpressLRS) and GHST
-- (ImmersionRC Ghost) frames exported by busnoop (`busnoop crsf SOURCE --export f.pcapng`,
-- link type USER2 = 149; `busnoop ghst SOURCE --export f.pcapng`, link type USER3 = 150; the
-- last lines below register them).
--
-- One packet is one frame as it was on the wire: ADDRESS LENGTH TYPE PAYLOAD CRC, LENGTH the
-- bytes after it (2..62), CRC-8 polynomial 0xD5 over TYPE and PAYLOAD. Types 0x28 and up
-- (CRSF) start the payload with destination and origin; command frames (0x32) carry a second
-- CRC-8, polynomial 0xBA, over TYPE .. command data. Numbers are named and scaled as busnoop's
-- table shows them (EdgeTX's sensor names, Betaflight's channel scale); the first one is
-- crsf.sensor / crsf.value, all of them crsf.parts. A bad CRC is expert info (error); bytes
-- busnoop exported that are no frame (garbage, a cut frame) are shown as such.
--
-- Install: copy or link into your personal Lua plugins folder (Help > About Wireshark >
-- Folders), or load it once: wireshark -X lua_script:busnoop-crsf.lua frames.pcapng
-- See docs/crsf.md in busnoop. License: as busnoop (MIT OR Apache-2.0).

local crsf = Proto("busnoop_crsf", "CRSF (busnoop)")
local ghst = Proto("busnoop_ghst", "GHST (busnoop)")

local crsf_devices = {
  [0x00] = "Broadcast", [0x0E] = "Cloud", [0x10] = "USB", [0x12] = "Bluetooth",
  [0x13] = "WiFi RX", [0x14] = "VRX", [0x80] = "OSD", [0x8A] = "Reserved", [0x90] = "ESC1",
  [0x91] = "ESC2", [0x92] = "ESC3", [0x93] = "ESC4", [0x94] = "ESC5", [0x95] = "ESC6",
  [0x96] = "ESC7", [0x97] = "ESC8", [0xB0] = "Crossfire", [0xB2] = "Crossfire",
  [0xC0] = "Current sensor", [0xC2] = "GPS", [0xC4] = "Blackbox", [0xC8] = "FC",
  [0xCA] = "Reserved", [0xCC] = "Race tag", [0xCE] = "VTX", [0xEA] = "Radio",
  [0xEC] = "Receiver", [0xEE] = "TX module", [0xEF] = "ELRS Lua", [0xF0] = "Reserved",
  [0xF2] = "Reserved",
}

local crsf_types = {
  [0x02] = "GPS", [0x03] = "GPSTime", [0x06] = "GPSExt", [0x07] = "Vario", [0x08] = "Battery",
  [0x09] = "Baro", [0x0A] = "Airspeed", [0x0B] = "Heartbeat", [0x0C] = "RPM", [0x0D] = "Temp",
  [0x0E] = "Voltages", [0x10] = "VTX", [0x14] = "LinkStats", [0x16] = "RC",
  [0x17] = "RCSubset", [0x18] = "RC11", [0x1C] = "LinkRX", [0x1D] = "LinkTX",
  [0x1E] = "Attitude", [0x1F] = "MAVLinkFC", [0x21] = "FlightMode", [0x22] = "ESPNow",
  [0x28] = "Ping", [0x29] = "DeviceInfo", [0x2B] = "ParamEntry", [0x2C] = "ParamRead",
  [0x2D] = "ParamWrite", [0x2E] = "ELRSStatus", [0x32] = "Command", [0x34] = "Logging",
  [0x3A] = "Radio", [0x3C] = "Game", [0x78] = "KISS", [0x79] = "KISS", [0x7A] = "MSPReq",
  [0x7B] = "MSPResp", [0x7C] = "MSPWrite", [0x7F] = "APLegacy", [0x80] = "APPassthru",
  [0x81] = "mLRS", [0x82] = "mLRS", [0xAA] = "MAVLink", [0xAC] = "MAVSysStatus",
}

local ghst_devices = {
  [0x80] = "Radio", [0x81] = "TX module", [0x82] = "FC", [0x83] = "Goggles", [0x84] = "Tee 1",
  [0x85] = "Tee 2", [0x86] = "Gateway", [0x87] = "5G clock", [0x88] = "TX module 115k",
  [0x89] = "Receiver",
}

local function new_fields(prefix)
  return {
    address = ProtoField.uint8(prefix .. ".address", "Address", base.HEX),
    device = ProtoField.string(prefix .. ".device", "Device"),
    length = ProtoField.uint8(prefix .. ".length", "Length", base.DEC),
    ftype = ProtoField.uint8(prefix .. ".frame_type", "Frame type", base.HEX),
    type_name = ProtoField.string(prefix .. ".type", "Type"),
    dest = ProtoField.uint8(prefix .. ".destination", "Destination", base.HEX),
    origin = ProtoField.uint8(prefix .. ".origin", "Origin", base.HEX),
    payload = ProtoField.bytes(prefix .. ".payload", "Payload"),
    sensor = ProtoField.string(prefix .. ".sensor", "Sensor"),
    value = ProtoField.string(prefix .. ".value", "Value"),
    unit = ProtoField.string(prefix .. ".unit", "Unit"),
    parts = ProtoField.string(prefix .. ".parts", "Numbers"),
    text = ProtoField.string(prefix .. ".text", "Text"),
    crc = ProtoField.uint8(prefix .. ".crc", "CRC", base.HEX),
    crc_status = ProtoField.string(prefix .. ".crc_status", "CRC status"),
    cmd_crc = ProtoField.uint8(prefix .. ".command_crc", "Command CRC", base.HEX),
    cmd_crc_status = ProtoField.string(prefix .. ".command_crc_status", "Command CRC status"),
  }
end

local cf = new_fields("crsf")
local gf = new_fields("ghst")
crsf.fields = cf
ghst.fields = gf

local function new_experts(prefix)
  return {
    crc = ProtoExpert.new(prefix .. ".crc.bad", "Bad CRC", expert.group.CHECKSUM,
      expert.severity.ERROR),
    cmd_crc = ProtoExpert.new(prefix .. ".command_crc.bad", "Bad command CRC",
      expert.group.CHECKSUM, expert.severity.WARN),
    short = ProtoExpert.new(prefix .. ".short", "Not a whole frame", expert.group.MALFORMED,
      expert.severity.ERROR),
  }
end

local ce = new_experts("crsf")
local ge = new_experts("ghst")
crsf.experts = { ce.crc, ce.cmd_crc, ce.short }
ghst.experts = { ge.crc, ge.cmd_crc, ge.short }

-- CRC-8 (MSB first, init 0) over bytes from..to of tvb.
local function crc8(tvb, from, to, poly)
  local c = 0
  for i = from, to do
    c = bit32.bxor(c, tvb(i, 1):uint())
    for _ = 1, 8 do
      if bit32.band(c, 0x80) ~= 0 then
        c = bit32.band(bit32.bxor(bit32.lshift(c, 1), poly), 0xFF)
      else
        c = bit32.band(bit32.lshift(c, 1), 0xFF)
      end
    end
  end
  return c
end

-- Fixed-point text of an integer with `prec` decimals, as busnoop prints its numbers.
local function fixed(n, prec)
  local neg = n < 0
  if neg then n = -n end
  local s
  if prec == 0 then
    s = string.format("%d", n)
  else
    local scale = math.floor(10 ^ prec + 0.5)
    s = string.format("%d.%0" .. prec .. "d", math.floor(n / scale), n % scale)
  end
  if neg then s = "-" .. s end
  return s
end

-- Readers over the payload (offset from the payload's start); nil past its end.
local function reader(tvb, start, len)
  local r = { pos = 0 }
  local function take(n)
    if r.pos + n > len then return nil end
    local range = tvb(start + r.pos, n)
    r.pos = r.pos + n
    return range
  end
  function r.u8() local t = take(1); return t and t:uint() end
  function r.i8() local t = take(1); return t and t:int() end
  function r.u16() local t = take(2); return t and t:uint() end
  function r.i16() local t = take(2); return t and t:int() end
  function r.u24() local t = take(3); return t and t:uint() end
  function r.i24()
    local v = r.u24()
    if v and v >= 0x800000 then v = v - 0x1000000 end
    return v
  end
  function r.i32() local t = take(4); return t and t:int() end
  function r.u32() local t = take(4); return t and t:uint() end
  function r.le_u16() local t = take(2); return t and t:le_uint() end
  function r.le_i16() local t = take(2); return t and t:le_int() end
  function r.le_i32() local t = take(4); return t and t:le_int() end
  function r.left() return len - r.pos end
  return r
end

-- The numbers of a frame: name, text, unit.
local function numbers()
  local list = {}
  function list.add(name, n, prec, unit)
    if n ~= nil then list[#list + 1] = { name, fixed(n, prec), unit } end
  end
  return list
end

local function bf_us(raw)
  return math.floor(0.62477120195241 * raw + 881 + 0.5)
end

local function rssi(b)
  if b >= 128 then return b - 256 end
  return -b
end

-- 11-bit (or `bits`-bit) little-endian fields of the payload.
local function unpack_bits(tvb, start, len, bits, count)
  local out, acc, have, i = {}, 0, 0, 0
  for k = 1, count do
    while have < bits do
      local b = 0
      if i < len then b = tvb(start + i, 1):uint() end
      acc = acc + b * (2 ^ have)
      i = i + 1
      have = have + 8
    end
    local scale = 2 ^ bits
    out[k] = math.floor(acc % scale)
    acc = math.floor(acc / scale)
    have = have - bits
  end
  return out
end

local function crsf_numbers(ty, tvb, start, len)
  local r = reader(tvb, start, len)
  local n = numbers()
  if ty == 0x16 or ty == 0x18 then
    local ch = unpack_bits(tvb, start, len, 11, 16)
    for k = 1, 16 do
      if ty == 0x16 then n.add("CH" .. k, bf_us(ch[k]), 0, "us")
      else n.add("CH" .. k, 9880 + ch[k] * 5, 1, "us") end
    end
  elseif ty == 0x17 and len >= 1 then
    local conf = r.u8()
    local first = bit32.band(conf, 0x1F)
    local res = bit32.band(bit32.rshift(conf, 5), 3)
    local bits = 10 + res
    local count = math.floor((len - 1) * 8 / bits)
    local ch = unpack_bits(tvb, start + 1, len - 1, bits, count)
    local scale = ({ 1, 5, 25, 125 })[res + 1]
    local base = ({ 988, 9880, 98800, 988000 })[res + 1]
    for k = 1, count do n.add("CH" .. (first + k), base + ch[k] * scale, res, "us") end
  elseif ty == 0x02 then
    n.add("Lat", r.i32(), 7, "deg"); n.add("Lon", r.i32(), 7, "deg")
    n.add("GSpd", r.u16(), 1, "km/h"); n.add("Hdg", r.u16(), 2, "deg")
    local alt = r.u16()
    if alt then n.add("Alt", alt - 1000, 0, "m") end
    n.add("Sats", r.u8(), 0, "")
  elseif ty == 0x06 then
    n.add("Fix", r.u8(), 0, "")
    for _, d in ipairs({ { "NSpd", 2, "m/s" }, { "ESpd", 2, "m/s" }, { "GVSp", 2, "m/s" },
        { "SAcc", 2, "m/s" }, { "TAcc", 1, "deg" }, { "EAlt", 0, "m" }, { "HAcc", 2, "m" },
        { "VAcc", 2, "m" } }) do
      n.add(d[1], r.i16(), d[2], d[3])
    end
    r.u8()
    n.add("HDOP", r.u8(), 1, ""); n.add("VDOP", r.u8(), 1, "")
  elseif ty == 0x07 then
    n.add("VSpd", r.i16(), 2, "m/s")
  elseif ty == 0x08 then
    n.add("RxBt", r.i16(), 1, "V"); n.add("Curr", r.i16(), 1, "A")
    n.add("Capa", r.u24(), 0, "mAh"); n.add("Bat%", r.u8(), 0, "%")
  elseif ty == 0x09 then
    local p = r.u16()
    if p then
      local dm
      if bit32.band(p, 0x8000) ~= 0 then dm = bit32.band(p, 0x7FFF) * 10 else dm = p - 10000 end
      n.add("BAlt", dm, 1, "m")
    end
    if len == 3 then
      local v = r.i8()
      local mag = math.floor((math.exp(math.abs(v) * 0.026) - 1) * 100)
      if v < 0 then mag = -mag end
      n.add("VSpd", mag, 2, "m/s")
    elseif len >= 4 then
      n.add("VSpd", r.i16(), 2, "m/s")
    end
  elseif ty == 0x0A then
    n.add("ASpd", r.u16(), 1, "km/h")
  elseif ty == 0x0C or ty == 0x0D or ty == 0x0E then
    local src = r.u8()
    local k = 0
    while src ~= nil do
      local v
      if ty == 0x0C then v = r.i24() elseif ty == 0x0D then v = r.i16() else v = r.u16() end
      if v == nil then break end
      k = k + 1
      local name
      if ty == 0x0C then name = "RPM" .. k
      elseif ty == 0x0D then name = "Tmp" .. k
      elseif src >= 128 then name = "Volt" .. k
      elseif k >= 10 then name = "Cl" .. k
      else name = "Cel" .. k end
      if src ~= 0 then name = name .. "_" .. src end
      local prec, unit = 0, "rpm"
      if ty == 0x0D then prec, unit = 1, "degC" elseif ty == 0x0E then prec, unit = 3, "V" end
      n.add(name, v, prec, unit)
    end
  elseif ty == 0x10 then
    r.u8()
    n.add("VPwr", r.u8(), 0, "dBm"); n.add("VFrq", r.u16(), 0, "MHz")
  elseif ty == 0x14 then
    local a, b = r.u8(), r.u8()
    if a then n.add("1RSS", rssi(a), 0, "dBm") end
    if b then n.add("2RSS", rssi(b), 0, "dBm") end
    n.add("RQly", r.u8(), 0, "%"); n.add("RSNR", r.i8(), 0, "dB")
    n.add("ANT", r.u8(), 0, ""); n.add("RFMD", r.u8(), 0, "")
    local pw = r.u8()
    local mw = ({ [0] = 0, 10, 25, 100, 500, 1000, 2000, 250, 50 })
    if pw and mw[pw] then n.add("TPWR", mw[pw], 0, "mW") end
    local t = r.u8()
    if t then n.add("TRSS", rssi(t), 0, "dBm") end
    n.add("TQly", r.u8(), 0, "%"); n.add("TSNR", r.i8(), 0, "dB")
  elseif ty == 0x1C then
    local a = r.u8()
    if a then n.add("RRSS", rssi(a), 0, "dBm") end
    n.add("RRSP", r.u8(), 0, "%"); n.add("RQly", r.u8(), 0, "%")
    n.add("RSNR", r.i8(), 0, "dB"); n.add("TPWR", r.u8(), 0, "dBm")
  elseif ty == 0x1D then
    local a = r.u8()
    if a then n.add("TRSS", rssi(a), 0, "dBm") end
    n.add("TRSP", r.u8(), 0, "%"); n.add("TQly", r.u8(), 0, "%")
    n.add("TSNR", r.i8(), 0, "dB"); n.add("RPWR", r.u8(), 0, "dBm")
    local f = r.u8()
    if f then n.add("TFPS", f * 10, 0, "Hz") end
  elseif ty == 0x1E then
    n.add("Ptch", r.i16(), 4, "rad"); n.add("Roll", r.i16(), 4, "rad")
    n.add("Yaw", r.i16(), 4, "rad")
  elseif ty == 0x3A and len >= 3 then
    r.u8(); r.u8()
    if r.u8() == 0x10 then
      n.add("Intv", r.u32(), 1, "us"); n.add("Offs", r.i32(), 1, "us")
    end
  end
  return n
end

local ghst_rf = { [0] = "Auto", "Norm", "Race", "Pure", "Long", "Unused", "Race2", "Pure2" }

local function ghst_type(addr, ty)
  if ty == 0x13 and addr ~= 0x82 then return "MenuCtrl" end
  if ty == 0x13 or ty == 0x33 then return "RCLink" end
  if (ty >= 0x10 and ty <= 0x1F) or (ty >= 0x30 and ty <= 0x3F) then return "RC" end
  if ty == 0x21 then if addr == 0x82 then return "MSPReq" end return "LinkStats" end
  if ty == 0x22 then if addr == 0x82 then return "MSPWrite" end return "VTXStats" end
  return ({ [0x20] = "Sync", [0x23] = "Battery", [0x24] = "Menu", [0x25] = "GPS",
    [0x26] = "GPS2", [0x27] = "MagBaro", [0x28] = "MSPResp" })[ty]
end

local function ghst_numbers(name, ty, tvb, start, len)
  local r = reader(tvb, start, len)
  local n = numbers()
  if name == "RC" or name == "RCLink" then
    local legacy = ty < 0x30
    local ch = unpack_bits(tvb, start, len, 12, 4)
    for k = 1, 4 do
      local v = ch[k]
      if legacy then v = math.floor(5 * v / 4) - 430 end
      n.add("CH" .. k, 98800 + v * 25, 2, "us")
    end
    r.pos = 6
    local low = bit32.band(ty, 0x0F)
    if low <= 2 then
      for k = 1, 4 do
        local a = r.u8()
        if a then
          if legacy then a = 880 + 5 * a else a = 988 + 4 * a end
          n.add("CH" .. (4 + 4 * low + k), a, 0, "us")
        end
      end
    elseif low == 3 then
      n.add("RQly", r.u8(), 0, "%")
      local s = r.u8()
      if s then n.add("RSSI", -s, 0, "dBm") end
      n.add("RFMD", r.u8(), 0, ""); n.add("TPWR", r.i8(), 0, "dBm")
    end
  elseif name == "Sync" then
    n.add("Intv", r.u32(), 1, "us"); n.add("Offs", r.i32(), 1, "us")
  elseif name == "LinkStats" then
    local s = r.u8()
    if s then n.add("RSSI", -s, 0, "dBm") end
    n.add("RQly", r.u8(), 0, "%"); n.add("RSNR", r.u8(), 0, "dB")
    n.add("TPWR", r.u16(), 0, "mW"); n.add("FRat", r.u16(), 0, "Hz")
    n.add("TLat", r.u16(), 0, "us")
    local m = r.u8()
    if m then n.add("RFMD", m, 0, ""); n.mode = ghst_rf[m] end
  elseif name == "VTXStats" then
    r.u8()
    n.add("VFrq", r.u16(), 0, "MHz"); n.add("VPwr", r.u16(), 0, "mW")
    r.u8()
    n.add("VChn", r.u8(), 0, "")
  elseif name == "Battery" then
    n.add("RxBt", r.le_u16(), 2, "V"); n.add("Curr", r.le_u16(), 2, "A")
    local c = r.le_u16()
    if c then n.add("Capa", c * 10, 0, "mAh") end
    n.add("RxV", r.u8(), 1, "V")
  elseif name == "GPS" then
    n.add("Lat", r.le_i32(), 7, "deg"); n.add("Lon", r.le_i32(), 7, "deg")
    n.add("Alt", r.le_i16(), 0, "m")
  elseif name == "GPS2" then
    local s = r.le_u16()
    if s then n.add("GSpd", math.floor((s * 36 + 50) / 100), 1, "km/h") end
    n.add("Hdg", r.le_u16(), 1, "deg"); n.add("Sats", r.u8(), 0, "")
    local d = r.le_u16()
    if d then n.add("Dist", d * 10, 0, "m") end
    n.add("HDir", r.le_u16(), 1, "deg")
  elseif name == "MagBaro" then
    local head, alt, vario = r.le_i16(), r.le_i16(), r.i8()
    r.le_u16(); r.le_u16()
    local flags = r.u8() or 0
    if bit32.band(flags, 1) ~= 0 then n.add("MHdg", head, 1, "deg") end
    if bit32.band(flags, 2) ~= 0 then n.add("BAlt", alt, 0, "m") end
    if bit32.band(flags, 4) ~= 0 then n.add("VSpd", vario, 2, "m/s") end
  end
  return n
end

-- Shared by both protocols: checks the frame shape, the CRC and shows the numbers.
local function dissect(tvb, pinfo, tree, proto, f, e, label, devices, is_start, type_of, numbers_of)
  pinfo.cols.protocol = label
  local t = tree:add(proto, tvb(), label)
  local n = tvb:len()
  if n < 1 then return 0 end
  local addr = tvb(0, 1):uint()
  local declared = n >= 2 and tvb(1, 1):uint() or nil
  if not is_start[addr] or declared == nil or declared < 2 or declared > 62
      or declared + 2 ~= n then
    -- Garbage, or a frame cut by the end of the input.
    t:add_proto_expert_info(e.short)
    if is_start[addr] and declared and declared >= 2 and declared <= 62 and n < declared + 2 then
      pinfo.cols.info = string.format("Truncated: %d of %d bytes", n, declared + 2)
    else
      pinfo.cols.info = string.format("Garbage: %d bytes", n)
    end
    return n
  end
  local ty = tvb(2, 1):uint()
  local name = type_of(addr, ty) or "Unknown"
  t:add(f.address, tvb(0, 1))
  t:add(f.device, devices[addr] or "")
  t:add(f.length, tvb(1, 1))
  t:add(f.ftype, tvb(2, 1))
  t:add(f.type_name, name)
  local plen = n - 4
  if plen > 0 then t:add(f.payload, tvb(3, plen)) end
  local want = crc8(tvb, 2, n - 2, 0xD5)
  local got = tvb(n - 1, 1):uint()
  local c = t:add(f.crc, tvb(n - 1, 1))
  local info = string.format("%s %s", devices[addr] or string.format("0x%02X", addr), name)
  if got ~= want then
    t:add(f.crc_status, "bad")
    c:add_proto_expert_info(e.crc)
    pinfo.cols.info = info .. string.format(" [bad CRC 0x%02X, expected 0x%02X]", got, want)
    return n
  end
  t:add(f.crc_status, "good")
  local start = 3
  if proto == crsf and ty >= 0x28 and ty ~= 0x34 and not (ty >= 0x7F and ty <= 0x82)
      and ty ~= 0xAA and ty ~= 0xAC and plen >= 2 then
    t:add(f.dest, tvb(3, 1))
    t:add(f.origin, tvb(4, 1))
    if ty == 0x32 and plen >= 4 then
      local cw = crc8(tvb, 2, n - 3, 0xBA)
      local cc = t:add(f.cmd_crc, tvb(n - 2, 1))
      if cw == tvb(n - 2, 1):uint() then
        t:add(f.cmd_crc_status, "good")
      else
        t:add(f.cmd_crc_status, "bad")
        cc:add_proto_expert_info(e.cmd_crc)
      end
    end
  end
  if proto == crsf and ty == 0x21 and plen > 0 then
    local s = tvb(3, plen):stringz()
    t:add(f.text, tvb(3, plen), s)
    info = info .. " " .. s
  end
  local nums = numbers_of(name, ty, tvb, start, plen)
  if #nums > 0 then
    t:add(f.sensor, nums[1][1])
    t:add(f.value, nums[1][2])
    t:add(f.unit, nums[1][3])
    local all = {}
    for k = 1, #nums do all[k] = nums[k][1] .. "=" .. nums[k][2] .. nums[k][3] end
    local text = table.concat(all, " ")
    t:add(f.parts, text)
    info = info .. " " .. text
    if nums.mode then info = info .. " (" .. nums.mode .. ")" end
  end
  pinfo.cols.info = info
  return n
end

local crsf_start = {}
for a, _ in pairs(crsf_devices) do crsf_start[a] = true end
local ghst_start = {}
for a = 0x80, 0x89 do ghst_start[a] = true end

function crsf.dissector(tvb, pinfo, tree)
  return dissect(tvb, pinfo, tree, crsf, cf, ce, "CRSF", crsf_devices, crsf_start,
    function(_, ty) return crsf_types[ty] end,
    function(_, ty, b, s, l) return crsf_numbers(ty, b, s, l) end)
end

function ghst.dissector(tvb, pinfo, tree)
  return dissect(tvb, pinfo, tree, ghst, gf, ge, "GHST", ghst_devices, ghst_start, ghst_type,
    ghst_numbers)
end

local encap = DissectorTable.get("wtap_encap")
local w = wtap_encaps or wtap
encap:add(w.USER2, crsf)
encap:add(w.USER3, ghst)
