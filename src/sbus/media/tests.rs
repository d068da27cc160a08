use super::super::telegram;
use super::*;

fn parts(data: &str) -> Vec<(String, f64)> {
    let mut buf = [Part::EMPTY; MAX_PARTS];
    let n = media_parts(data, &mut buf);
    buf[..n]
        .iter()
        .map(|p| (format!("{}={}", p.name, p.text), p.value))
        .collect()
}

#[test]
fn media_values_are_numbers() {
    assert_eq!(
        parts("R0=305419896 R2=-1245334075"),
        [
            ("R0=305419896".to_owned(), 305419896.0),
            ("R2=-1245334075".to_owned(), -1245334075.0)
        ]
    );
    assert_eq!(parts("F3=0"), [("F3=0".to_owned(), 0.0)]);
    for none in [
        "R0..R3",
        "",
        "R (run)",
        "ACK (0x0000)",
        "display=12",
        "R1=1 n=3",
        "Z=1 N=0 E=0",
        "R=5",
    ] {
        assert!(parts(none).is_empty(), "{none}");
    }
}

/// The rule as first written with `str::split` (the reference for the byte scanner).
fn reference(data: &str) -> Vec<(String, f64)> {
    let mut v = Vec::new();
    for tok in data.split(' ') {
        let Some((name, text)) = tok.split_once('=') else {
            return Vec::new();
        };
        let medium = name.chars().next().is_some_and(|c| "RFIOTC".contains(c));
        let addr = name.len() > 1 && name.bytes().skip(1).all(|b| b.is_ascii_digit());
        let Ok(value) = text.parse::<i64>() else {
            return Vec::new();
        };
        if !medium || !addr || v.len() == MAX_PARTS {
            return Vec::new();
        }
        v.push((format!("{name}={text}"), value as f64));
    }
    v
}

#[test]
fn the_byte_scanner_reads_like_the_reference_and_the_small_buffer_like_the_large() {
    let many = |n: usize| {
        (0..n)
            .map(|i| format!("F{i}={}", i % 2))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut cases: Vec<String> = [
        "R0=1",
        "R0=1 ",
        " R0=1",
        "R0=1  R1=2",
        "R0=1=2",
        "R0==1",
        "=1",
        "R0=",
        "R0=+7 T12=-3 C1=0",
        "R00=1 O7=99999999999",
        "R0=99999999999999999999",
        "é5=1",
        "Ré=1",
        "R1=1 é",
        "R1=+",
        "R1=-",
        "R1=+-5",
        "R1=-0 R2=+0",
        "R1=-9223372036854775808",
        "R1=-9223372036854775809",
        "R1=9223372036854775807",
        "R1=9223372036854775808",
        "R1=5x",
        "R1x=5",
        "r1=5",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for n in [1, 15, 16, 17, 127, 128, 129, 200] {
        cases.push(many(n));
    }
    for data in &cases {
        let want = reference(data);
        assert_eq!(parts(data), want, "{data}");
        let tokens = 1 + data.bytes().filter(|&b| b == b' ').count();
        if tokens <= FEW_PARTS {
            let mut buf = [Part::EMPTY; FEW_PARTS];
            let n = media_parts(data, &mut buf);
            assert_eq!(n, want.len(), "{data}");
        }
    }
    assert_eq!(parts(&many(128)).len(), 128);
    assert!(parts(&many(129)).is_empty());
}

/// The parts of a row whose Data cell was recorded as a media list, as `put_row` builds
/// them; `None` when nothing was recorded for this text.
fn recorded(data: &str, media: &MediaSpans) -> Option<Vec<(String, f64)>> {
    if media.len != Some(data.len()) {
        return None;
    }
    if media.spans.len() > MAX_PARTS {
        return Some(Vec::new());
    }
    let parts = crate::row::Parts::Spans {
        text: data,
        spans: &media.spans,
    };
    Some(
        parts
            .iter()
            .map(|p| (format!("{}={}", p.name, p.text), p.value))
            .collect(),
    )
}

/// Every command with bodies of many lengths and values, and the responses to the
/// requests: the numbers recorded while the Data cell is written are the ones reading the
/// cell back gives.
#[test]
fn recorded_media_lists_give_the_parts_read_from_the_text() {
    let mut seed = 0x2545_F491_u32;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed
    };
    let mut lists = 0;
    for cmd in 0..=255u8 {
        for len in [0usize, 1, 2, 3, 4, 5, 7, 8, 11, 19, 35, 67, 131, 200, 300] {
            for _ in 0..3 {
                let mut body: Vec<u8> = (0..len).map(|_| next() as u8).collect();
                if len > 0 {
                    body[0] = (next() % 40) as u8;
                }
                let (mut sensor, mut data, mut media) =
                    (String::new(), String::new(), MediaSpans::default());
                let t = telegram::describe_request_media(
                    1,
                    cmd,
                    &body,
                    &mut sensor,
                    &mut data,
                    Some(&mut media),
                );
                if let Some(got) = recorded(&data, &media) {
                    lists += 1;
                    assert_eq!(got, parts(&data), "request {cmd:02X} {data}");
                }
                for plen in [0usize, 1, 4, 8, 16, 17, 64, 128] {
                    let payload: Vec<u8> = (0..plen).map(|_| next() as u8).collect();
                    let (mut sensor, mut data, mut media) =
                        (String::new(), String::new(), MediaSpans::default());
                    telegram::describe_response_media(
                        &t.info,
                        &payload,
                        &mut sensor,
                        &mut data,
                        Some(&mut media),
                    );
                    if let Some(got) = recorded(&data, &media) {
                        lists += 1;
                        assert_eq!(got, parts(&data), "response to {cmd:02X} {data}");
                    }
                }
            }
        }
    }
    assert!(lists > 300, "{lists}");
    // Text that merely looks like a list is not recorded: it is read back.
    let t = telegram::describe_request(1, 0x20, &[], &mut String::new(), &mut String::new());
    let (mut data, mut media) = (String::new(), MediaSpans::default());
    let sensor = &mut String::new();
    telegram::describe_response_media(&t.info, b"R1=5", sensor, &mut data, Some(&mut media));
    assert_eq!(recorded(&data, &media), None);
    assert_eq!(parts(&data).len(), 1);
}

/// The padded check against the text checked alone: every length, blocks that are ASCII
/// after the text and blocks that are not.
#[test]
fn ascii_text_is_the_text_alone() {
    let mut block = [0u8; 80];
    for (i, b) in block.iter_mut().enumerate() {
        *b = b' ' + (i % 90) as u8;
    }
    for after in [None, Some(0xC3u8), Some(0xFF), Some(0x80)] {
        for len in 0..=block.len() + 3 {
            let mut b = block;
            if let Some(x) = after {
                for k in (len..b.len()).step_by(5) {
                    b[k] = x;
                }
            }
            let want = std::str::from_utf8(&b[..len.min(b.len())]).unwrap();
            assert_eq!(ascii_text(&b, len), want, "{len} {after:?}");
        }
    }
}

/// The block-wise list writer against the text written piece by piece with `format!`:
/// every medium, addresses and values at the digit-count edges, wrapping addresses, lists
/// longer than a block, and a cell that already holds text (nothing recorded then).
#[test]
fn lists_match_the_text_written_piece_by_piece() {
    let media = LETTERED;
    let values: Vec<u32> = vec![
        0,
        1,
        9,
        10,
        99,
        100,
        12345,
        999_999_999,
        1_000_000_000,
        i32::MAX as u32,
        i32::MIN as u32,
        u32::MAX,
        u32::MAX - 9,
        (-100i32) as u32,
    ];
    let addrs = [0u32, 7, 9, 95, 999, 65530, 99_999_998, u32::MAX - 2];
    for &elem in &media {
        for &addr in &addrs {
            for count in [1usize, 2, 5, 14, 40, 128] {
                let words: Vec<u32> = (0..count).map(|i| values[i % values.len()]).collect();
                let data: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
                let mut want = String::new();
                let mut want_spans = Vec::new();
                for (i, &w) in words.iter().enumerate() {
                    if i > 0 {
                        want.push(' ');
                    }
                    let start = want.len();
                    want.push_str(&format!("{}{}", elem.prefix(), addr.wrapping_add(i as u32)));
                    let eq = want.len();
                    let (text, value) = if elem.is_unsigned() {
                        (w.to_string(), w as f64)
                    } else {
                        ((w as i32).to_string(), w as i32 as f64)
                    };
                    want.push('=');
                    want.push_str(&text);
                    want_spans.push((start as u32, eq as u32, want.len() as u32, value));
                }
                let mut got = String::new();
                let mut m = MediaSpans::default();
                let first = push_words(&mut got, elem, 0, addr, &data, Some(&mut m));
                assert_eq!(got, want, "{elem:?} {addr} {count}");
                assert_eq!(got[..first], format!("{}{addr}", elem.prefix()));
                assert_eq!(m.len, Some(got.len()));
                let spans: Vec<_> = m
                    .spans
                    .iter()
                    .map(|s| (s.start, s.eq, s.end, s.value))
                    .collect();
                assert_eq!(spans, want_spans, "{elem:?} {addr} {count}");
                // after other text: the same text, nothing recorded
                let mut after = String::from("x");
                let mut m2 = MediaSpans::default();
                push_words(&mut after, elem, 0, addr, &data, Some(&mut m2));
                assert_eq!(after, format!("x{want}"));
                assert_eq!((m2.len, m2.spans.len()), (None, 0));

                // bits: element i is bit i % 8 of byte i / 8
                let bytes: Vec<u8> = words.iter().map(|&w| (w ^ (w >> 11)) as u8).collect();
                for bits in [1u32, 7, 8, 9, count as u32 * 8, count as u32 * 8 + 3] {
                    let mut want = String::new();
                    let mut want_spans = Vec::new();
                    for i in 0..bits.min(bytes.len() as u32 * 8) {
                        if i > 0 {
                            want.push(' ');
                        }
                        let start = want.len();
                        want.push_str(&format!("{}{}", elem.prefix(), addr.wrapping_add(i)));
                        let eq = want.len();
                        let bit = bytes[(i / 8) as usize] >> (i % 8) & 1;
                        want.push_str(&format!("={bit}"));
                        want_spans.push((start as u32, eq as u32, want.len() as u32, bit as f64));
                    }
                    let mut got = String::new();
                    let mut m = MediaSpans::default();
                    let first = push_bits(&mut got, elem, addr, bits, &bytes, Some(&mut m));
                    assert_eq!(got, want, "{elem:?} {addr} {bits}");
                    assert_eq!(got[..first], format!("{}{addr}", elem.prefix()));
                    let spans: Vec<_> = m
                        .spans
                        .iter()
                        .map(|s| (s.start, s.eq, s.end, s.value))
                        .collect();
                    assert_eq!(spans, want_spans);
                }
            }
            let mut name = String::from("a");
            push_elem(&mut name, elem, 0, addr);
            assert_eq!(name, format!("a{}{addr}", elem.prefix()));
        }
    }
}

#[test]
fn names_from_the_first_name_are_the_names_formatted() {
    // The list's names copied from the first name written for the Sensor # cell, and counted
    // up from there, as the names formatted anew.
    let addrs = [
        0,
        1,
        9,
        10,
        57,
        99,
        999,
        65_535,
        99_999_999,
        100_000_000,
        u32::MAX - 1,
    ];
    for letter in [b'R', b'T', b'C', b'F'] {
        for addr in addrs.into_iter().chain([u32::MAX]) {
            for (range, count) in [(false, 3), (true, 1), (true, 7)] {
                let l = LazyWords {
                    letter,
                    addr,
                    sign_bit: 0,
                    count,
                    name: true,
                    range,
                };
                let mut copied = Names::of_first(&l.first_name(), letter, addr);
                let mut formatted = Names::new(letter, addr);
                for _ in 0..12 {
                    assert_eq!(copied.len, formatted.len, "{letter} {addr}");
                    assert_eq!(
                        copied.text[..copied.len],
                        formatted.text[..formatted.len],
                        "{letter} {addr}"
                    );
                    assert_eq!(copied.addr, formatted.addr);
                    copied.step();
                    formatted.step();
                }
            }
        }
    }
}
