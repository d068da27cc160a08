use super::text::int_reading;
use super::*;

#[test]
fn response_time_is_push_ms() {
    for micros in [
        0,
        1,
        999,
        1000,
        1822,
        9999,
        10_000,
        10_001,
        123_456_789,
        u64::MAX,
    ] {
        let (mut ours, mut reference) = (String::new(), String::new());
        push_ms3(&mut ours, micros);
        crate::fmt::push_ms(&mut reference, micros);
        assert_eq!(ours, reference, "{micros} µs");
    }
}

#[test]
fn payload_reading_is_the_default_value() {
    for payload in [
        &[][..],
        &[0x7F],
        &[0x80],
        &[0xFF, 0xFF],
        &[0x23, 0x01],
        &[1, 2, 3],
        &[0, 0, 0, 0x80],
        &[0xFF; 4],
        &[0xFF, 0xFF, 0xFF, 0x7F],
        &[0x00, 0xCA, 0x9A, 0x3B],
        &[0xFF, 0xC9, 0x9A, 0x3B],
        &[0x00, 0x80],
        &[0xFF, 0x7F],
        &[1, 2, 3, 4, 5],
    ] {
        let mut data = String::new();
        push_hex(&mut data, payload);
        let mut value = String::new();
        let reading = super::super::values::read_default(payload, &mut value);
        match int_reading(payload) {
            Some((unsigned, signed)) => {
                let at = push_reading(&mut data, unsigned, signed);
                assert_eq!(&data[at], value);
                assert_eq!(reading, Reading::Number(unsigned as f64));
            }
            None => assert_eq!(reading, Reading::None),
        }
        let mut whole = String::new();
        push_payload(&mut whole, payload);
        assert_eq!(data, whole);
    }
    let mut s = String::new();
    push_payload(&mut s, &[0xFF, 0xFF]);
    assert_eq!(s, "FF FF (65535, -1)");
}

#[test]
fn one_byte_data_is_hex_and_push_reading() {
    for b in 0..=255u8 {
        let (mut table, mut general) = ("AB".to_string(), "AB".to_string());
        let Some((at, value)) = push_data(&mut table, &[b]) else {
            panic!("{b}: no reading");
        };
        push_hex(&mut general, &[b]);
        let general_at = push_reading(&mut general, b as u32, b as i8 as i32);
        assert_eq!(table, general, "{b}");
        assert_eq!(at, general_at, "{b}");
        assert_eq!(&table[at], b.to_string(), "{b}");
        assert_eq!(value, b as u64);
    }
}

#[test]
fn stream_times_in_64_bits_are_the_128_bit_quotient() {
    let map = |baud| {
        Mapper::new(&Options {
            baud,
            ..Options::default()
        })
    };
    for baud in [1, 9600, 115_200, 1_000_000, u32::MAX] {
        let m = map(baud);
        for pos in [
            0,
            1,
            7,
            8_388_608,
            1_844_674_407,
            1_844_674_408,
            u64::MAX / 3,
            u64::MAX,
        ] {
            let exact = pos as u128 * BITS_PER_BYTE as u128 * 1_000_000_000 / baud as u128;
            assert_eq!(
                m.nanos_at(pos),
                exact.min(u64::MAX as u128) as u64,
                "{pos} @ {baud}"
            );
        }
    }
}
