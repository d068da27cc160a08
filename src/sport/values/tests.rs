use super::*;

fn d(app_id: u16, value: u32) -> (String, String, &'static str) {
    let (mut s, mut v) = (String::new(), String::new());
    let unit = decode(app_id, value, &mut s, &mut v);
    (s, v, unit)
}

#[test]
fn push_2_is_two_digits_at_least() {
    for v in 0..=255u8 {
        let mut s = String::from("x");
        push_2(&mut s, v);
        assert_eq!(s, format!("x{v:02}"));
    }
}

/// The constant texts of FLVSS frames are what formatting the numbers wrote, for every
/// first index and count.
#[test]
fn cell_texts_match_formatting() {
    for n in 0..16 {
        assert_eq!(CELL_COUNTS[n], format!("count={n}"));
        assert_eq!(CELL_KEYS[n], format!(" cell{}=", n + 1));
    }
    for index in 0..16u32 {
        for count in 0..16u32 {
            let value = index | count << 4 | 1959 << 8 | 1000 << 20;
            let (mut data, mut nums) = (String::new(), SportNumbers::default());
            cells(value, &mut data, &mut nums);
            let mut want = format!("count={count} cell{}=3.918", index + 1);
            if index + 1 < count {
                want.push_str(&format!(" cell{}=2.000", index + 2));
            }
            assert_eq!(data, want, "index {index} count {count}");
        }
    }
}

#[test]
fn hex_ids() {
    for id in [0u16, 1, 0x10, 0x0210, 0x5100, 0xF101, 0xFFFF] {
        let (mut a, mut b) = (String::new(), String::new());
        push_sensor_no(&mut a, id);
        push_hex_id(&mut b, id);
        assert_eq!(a, format!("0x{id:04X}"));
        assert_eq!(b, a);
    }
}

#[test]
fn sample_names_and_scaling() {
    assert_eq!(d(0x0100, 6543), ("Alt".into(), "65.43".into(), "m"));
    assert_eq!(d(0x0110, 0), ("Vario".into(), "0.00".into(), "m/s"));
    assert_eq!(d(0x0200, 0), ("Amps".into(), "0.0".into(), "A"));
    assert_eq!(d(0x0210, 0), ("Volts".into(), "0.00".into(), "V"));
    assert_eq!(d(0x0110, 0xFFFF_FF6A).1, "-1.50");
    assert_eq!(d(0x010F, 100).0, "Alt", "instance nibble keeps the name");
}

#[test]
fn packed_values() {
    assert_eq!(d(0x0300, 0x8188_0D30).1, "count=3 cell1=4.122 cell2=4.144");
    assert_eq!(d(0x0300, 0x0008_3432).1, "count=3 cell3=4.200");
    assert_eq!(d(0x0800, 0x8071_0700).1, "lon=12.3456000");
    assert_eq!(d(0x0800, 0x4071_0700).1, "lat=-12.3456000");
    assert_eq!(
        d(0x0850, 0x0E07_0BFF),
        ("Date".into(), "2014-07-11".into(), "")
    );
    assert_eq!(
        d(0x0850, 0x1629_0100),
        ("Time".into(), "22:41:01".into(), "")
    );
    assert_eq!(d(0xF104, 0x9612_0062).1, "5.07");
    assert_eq!(d(0xF101, 0x9612_005A).1, "90");
    assert_eq!(
        d(0x0006, 0xD007),
        ("Hub Cell".into(), "idx1=4.000".into(), "V")
    );
    assert_eq!(d(0x0010, 638).0, "Hub BARO_ALT_BP");
    assert_eq!(d(0x0B00, 5000 | 120 << 16).1, "RB1V=5.000V RB1A=1.20A");
    assert_eq!(d(0x0730, 0xFF9C_0064).1, "Roll=1.00deg Ptch=-1.00deg");
    assert_eq!(d(0x0E50, 5000 | 1200 << 16).1, "BecV=5.000V BecA=1.200A");
    assert_eq!(d(0x0B60, 123 | 456 << 16).1, "Erpm=12300rpm EscC=456mAh");
    assert_eq!(d(0x0B20, 0x0001_0004).1, "RBCS=CH3 KO RBS=Rx1 Ovl");
    assert_eq!(d(0x0B20, 0).1, "RBCS=OK RBS=Rx OK");
    assert_eq!(d(0x0B80, 0x101).1, "CH17 KO,S.P Ovl");
    assert_eq!(
        d(0x6800, 0x0023_4A0C).1,
        "SrvA=1.2A SrvV=7.4V SrvT=35degC SrvS=OK"
    );
    assert_eq!(d(0xF107, 20).1, "100");
    assert_eq!(d(0xF010, 5).1, "95");
}

/// (phys, app ID, value) → (Value text, unit of the Value, every part as name=text).
fn n(phys: u8, app_id: u16, value: u32) -> (String, &'static str, String) {
    let (mut s, mut v, mut nums) = (String::new(), String::new(), SportNumbers::default());
    let unit = decode_numbers(phys, app_id, value, &mut s, &mut v, &mut nums);
    let parts = nums.with_parts(|p| {
        p.iter()
            .map(|p| format!("{}={}{}", p.name, p.text, p.unit))
            .collect::<Vec<_>>()
            .join(" ")
    });
    (nums.first_text().to_owned(), unit, parts)
}

#[test]
fn full_wire_precision_and_numbers() {
    // 12 bits of 2 mV: raw 1959 (0x7A7) is 3.918 V, where the radio keeps 3.91.
    let v = 0x7A7 << 8 | 1 << 4;
    assert_eq!(d(0x0300, v).1, "count=1 cell1=3.918");
    assert_eq!(
        n(1, 0x0300, v),
        ("3.918".into(), "V", "Cell1=3.918V".into())
    );
    assert_eq!(
        n(1, 0x0300, 0x8188_0D30).2,
        "Cell1=4.122V Cell2=4.144V",
        "both cells of a frame are parts"
    );
    assert_eq!(n(1, 0x0300, 0x0008_3432).2, "Cell3=4.200V");
    assert_eq!(
        n(0, 0x0210, 1234),
        ("12.34".into(), "V", "VFAS=12.34V".into())
    );
    assert_eq!(n(0, 0x0200, 25).2, "Curr=2.5A");
    assert_eq!(n(0, 0x0110, 0xFFFF_FF6A).2, "VSpd=-1.50m/s");
    assert_eq!(n(3, 0x0800, 0x4071_0700).2, "Lat=-12.3456000deg");
    assert_eq!(n(3, 0x0800, 0x8000_0001).2, "Lon=0.0000017deg");
    // A pair's Value is its first half, with that half's unit.
    assert_eq!(
        n(0, 0x0B00, 5000 | 120 << 16),
        ("5.000".into(), "V", "RB1V=5.000V RB1A=1.20A".into())
    );
    assert_eq!(
        n(0, 0x6800, 0x0023_4A0C).2,
        "SrvA=1.2A SrvV=7.4V SrvT=35degC"
    );
    assert_eq!(n(24, 0xF104, 0x62).2, "RxBt=5.07V");
    assert_eq!(n(0, 0x5100, 12345).2, "0x5100=12345");
    assert_eq!(n(0, 0x0010, 638).2, "BARO_ALT_BP=638");
    // Text values carry no number.
    assert_eq!(n(3, 0x0850, 0x0E07_0BFF).2, "");
    assert_eq!(n(0, 0x0B20, 0).2, "");
}

#[test]
fn acc_scale_follows_the_sender() {
    // Flight controllers (slot 0x1B, Betaflight/INAV) send 0.01 g: FF FF FF FF is -0.01 g.
    assert_eq!(n(FC_PHYS, 0x0700, 0xFFFF_FFFF).0, "-0.01");
    assert_eq!(n(FC_PHYS, 0x0720, 100).0, "1.00");
    // FrSky sensors and EdgeTX's table: 0.001 g.
    assert_eq!(n(23, 0x0700, 0xFFFF_FFFF).0, "-0.001");
    assert_eq!(n(23, 0x0710, 1000).2, "AccY=1.000g");
}

#[test]
fn unknown_ids_show_hex_label_and_raw_value() {
    assert_eq!(d(0x5100, 12345), ("0x5100".into(), "12345".into(), ""));
    assert_eq!(d(0x0420, 7).0, "0x0420");
    let mut s = String::new();
    push_sensor_no(&mut s, 0x0210);
    assert_eq!(s, "0x0210");
}
