use super::super::part_keys::PartKeys;
use super::*;

/// Every length up to 40 and every position of a marked byte: the word tests agree with
/// the byte tests.
#[test]
fn scans_agree_with_byte_tests() {
    type WordTest<'a> = &'a dyn Fn(u64) -> u64;
    type ByteTest<'a> = &'a dyn Fn(u8) -> bool;
    let tests: [(WordTest<'_>, ByteTest<'_>); 4] = [
        (&below_0x20, &|b| b < 0x20),
        (&not_printable, &|b| !(0x20..0x7F).contains(&b)),
        (&|x| zero_byte(x ^ rep(b'"')), &|b| b == b'"'),
        (&|x| zero_byte(x ^ rep(b',')), &|b| b == b','),
    ];
    let specials = [
        0x00, 0x01, 0x09, 0x0A, 0x0D, 0x1F, 0x20, 0x21, 0x22, 0x2C, 0x5C, 0x7E, 0x7F, 0x80, 0xC3,
        0xFE, 0xFF,
    ];
    for (word_test, byte_test) in tests {
        for n in 0..40 {
            for &fill in &[b'a', b' ', b'~', 0x21, 0xFF, 0x80] {
                let base = vec![fill; n];
                assert_eq!(
                    scan(&base, word_test) != 0,
                    base.iter().any(|&b| byte_test(b)),
                    "n {n} fill {fill:#x}"
                );
                for at in 0..n {
                    for &sp in &specials {
                        let mut s = base.clone();
                        s[at] = sp;
                        assert_eq!(
                            scan(&s, word_test) != 0,
                            s.iter().any(|&b| byte_test(b)),
                            "n {n} at {at} byte {sp:#x} fill {fill:#x}"
                        );
                    }
                }
            }
        }
    }
}

/// The spans' copy path writes what the member-by-member path writes, for texts with and
/// without bytes to escape (quotes, backslashes, control characters, non-ASCII), empty
/// names and numbers, and spans off the text or off its character boundaries.
#[test]
fn json_spans_write_what_each_member_writes() {
    let texts = [
        "R57=-859895076 R58=12 F3=0",
        "a=1",
        "=5 x= y=7",
        "q\"=1 b\\=2",
        "t\tab=3 n\nl=4",
        "caf\u{e9}=1 z=2",
        "",
    ];
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    let mut next = |n: u32| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % u64::from(n)) as u32
    };
    for text in texts {
        let n = text.len() as u32;
        // the spans a writer records, then random ones, some off the text
        let mut lists: Vec<Vec<PartSpan>> = vec![
            text.split(' ')
                .scan(0u32, |at, tok| {
                    let start = *at;
                    *at += tok.len() as u32 + 1;
                    let eq = start + tok.find('=').unwrap_or(tok.len()) as u32;
                    Some(PartSpan {
                        start,
                        eq,
                        end: start + tok.len() as u32,
                        value: 1.0,
                    })
                })
                .collect(),
        ];
        for _ in 0..200 {
            let k = next(5) as usize;
            lists.push(
                (0..k)
                    .map(|_| {
                        let (a, b, c) = (next(n + 3), next(n + 3), next(n + 3));
                        let eq = if next(9) == 0 { u32::MAX } else { b };
                        PartSpan {
                            start: a,
                            eq,
                            end: c,
                            value: 0.0,
                        }
                    })
                    .collect(),
            );
        }
        for spans in &lists {
            let parts = Parts::Spans { text, spans };
            // The same members as a list: written as `Parts::List`.
            let list: Vec<Part<'_>> = parts.iter().collect();
            for room in [8, 30, 70] {
                let line = |parts: Parts<'_>| {
                    let mut buf = vec![0; room];
                    let len = write_line(&mut buf, 0, |w| {
                        w.put(b"{\"data\":null");
                        w.json_parts(parts)
                    });
                    buf.truncate(len);
                    buf
                };
                let mut slow = vec![0; room];
                let slow_len = write_line(&mut slow, 0, |w| {
                    w.put(b"{\"data\":null");
                    w.put(b",\"parts\":{");
                    for (i, p) in parts.iter().enumerate() {
                        w.json_member_pieces(i, &p);
                    }
                    w.byte(b'}');
                });
                let slow = &slow[..slow_len];
                assert_eq!(line(parts), slow, "{text:?} {spans:?} {room}");
                assert_eq!(line(Parts::List(&list)), slow, "{text:?} {spans:?} {room}");
            }
        }
    }
}

/// A member copied in one piece is what the piece-by-piece writes give: names short,
/// long, empty or to escape, numbers short and long, near the end of the room or not.
#[test]
fn json_member_within_writes_what_each_piece_writes() {
    let names = [
        "CH1",
        "",
        "a\"b",
        "x\ty",
        "A_rather_long_name_of_a_part",
        "caf\u{e9}",
    ];
    let numbers = ["1", "-0.5", "1234567890123456789012345678901234567890"];
    for pre in [&b","[..], b",\"parts\":{"] {
        for name in names {
            for number in numbers {
                for room in [8, 40, 70, 200] {
                    let write = |w: &mut W<'_>, fast: bool| {
                        w.put(b"{\"data\":");
                        let a = w.len();
                        w.put(number.as_bytes());
                        let b = w.len();
                        if fast {
                            w.json_member_within(pre, name, a, b);
                        } else {
                            w.put(pre);
                            w.json_str(name);
                            w.byte(b':');
                            w.put(number.as_bytes());
                        }
                    };
                    let mut fast = vec![0; room];
                    let n = write_line(&mut fast, 0, |w| write(w, true));
                    let mut slow = vec![0; room];
                    let m = write_line(&mut slow, 0, |w| write(w, false));
                    assert_eq!(&fast[..n], &slow[..m], "{name:?} {number:?} {room}");
                }
            }
        }
    }
}

/// A row's members from a list's keys made by the compiler, with one room check: what
/// [`W::json_key_within`] and [`W::json_key_text`] write member by member, first or not,
/// for every count of members, numbers short and long (then nothing is written and the
/// caller writes member by member), near the end of the room or not.
#[test]
fn listed_part_keys_write_what_each_member_writes() {
    use super::super::part_keys::PartNames;
    static NAMES: PartNames<4> = PartNames::new(["CH1", "FrameLost", "Bat%", "ABCDEFGHIJKL"]);
    let numbers = [
        ["1", "-0.5", "22", "3"],
        ["1500", "1", "-1234567.1234567", "0"],
        ["1", "1234567890123456789012345678901234567890", "2", "3"],
    ];
    for first in [true, false] {
        for number in numbers {
            for n in 0..=4 {
                for room in [8, 40, 70, 150, 200, 260, 400] {
                    let write = |w: &mut W<'_>, fast: u8| {
                        w.put(b"{\"data\":\"");
                        let mut marks = [Mark::default(); 4];
                        for (i, num) in number.iter().enumerate() {
                            if i > 0 {
                                w.byte(b' ');
                            }
                            let a = w.len() as u32;
                            w.put(num.as_bytes());
                            marks[i] = Mark::new(a, w.len() as u32);
                        }
                        w.byte(b'"');
                        let pieces = |w: &mut W<'_>| {
                            for (i, m) in marks[..n].iter().enumerate() {
                                let (key, k) = (&NAMES.keys[i], usize::from(NAMES.lens[i]));
                                if fast == 2 {
                                    let t = number[i].as_bytes();
                                    w.json_key_text(first && i == 0, key, k, t);
                                } else {
                                    let (a, b) = (m.start as usize, m.end as usize);
                                    w.json_key_within(first && i == 0, key, k, a, b);
                                }
                            }
                        };
                        match fast {
                            0 | 2 => pieces(w),
                            1 => {
                                if !w.json_keys_within(first, &NAMES.keys, &NAMES.lens, &marks[..n])
                                {
                                    pieces(w)
                                }
                            }
                            _ => {
                                if !w.json_keys_text(first, &NAMES.keys, &NAMES.lens, &number[..n])
                                {
                                    pieces(w)
                                }
                            }
                        }
                        w.put(b"}\n");
                    };
                    let line = |fast: u8| {
                        let mut buf = vec![0; room];
                        let len = write_line(&mut buf, 0, |w| write(w, fast));
                        buf.truncate(len);
                        String::from_utf8(buf).unwrap()
                    };
                    let want = line(0);
                    assert_eq!(line(1), want, "{first} {number:?} {n} {room}");
                    assert_eq!(line(2), want, "{first} {number:?} {n} {room}");
                    assert_eq!(line(3), want, "{first} {number:?} {n} {room}");
                }
            }
        }
    }
}

/// A member from its kept key, first or not, and a member with its number's text: what
/// [`W::json_member_within`] and the pieces write, for names kept or not (empty, long, to
/// escape, the same text at another address), numbers short and long, near the end of the
/// room or not.
#[test]
fn kept_part_keys_write_what_each_piece_writes() {
    let owned = String::from("CH1");
    let names = [
        "CH1",
        owned.as_str(),
        "",
        "a\"b",
        "x\ty",
        "A_rather_long_name_of_a_part",
        "ABCDEFGHIJKL",
        "ABCDEFGHIJKLM",
        "caf\u{e9}",
        "FrameLost",
        "Bat%",
    ];
    let numbers = ["1", "-0.5", "1234567890123456789012345678901234567890"];
    let mut keys = PartKeys::new();
    for round in 0..2 {
        for first in [true, false] {
            for name in names {
                for number in numbers {
                    for room in [8, 40, 70, 200] {
                        let pre: &[u8] = if first { b",\"parts\":{" } else { b"," };
                        let key = keys.get(name).copied();
                        assert_eq!(
                            key.is_some(),
                            (1..=PartKeys::NAME).contains(&name.len())
                                && !name.contains(['"', '\t']),
                            "{name:?}"
                        );
                        let write = |w: &mut W<'_>, fast: u8| {
                            w.put(b"{\"data\":");
                            let a = w.len();
                            w.put(number.as_bytes());
                            let b = w.len();
                            match (fast, key) {
                                (1, Some(key)) => {
                                    w.json_key_within(first, &key, name.len() + 4, a, b)
                                }
                                (2, Some(key)) => {
                                    w.json_key_text(first, &key, name.len() + 4, number.as_bytes())
                                }
                                (0, _) => w.json_member_within(pre, name, a, b),
                                _ => {
                                    w.put(pre);
                                    w.json_str(name);
                                    w.byte(b':');
                                    w.put(number.as_bytes());
                                }
                            }
                        };
                        let mut want = vec![0; room];
                        let m = write_line(&mut want, 0, |w| write(w, 3));
                        for fast in 0..3 {
                            let mut got = vec![0; room];
                            let n = write_line(&mut got, 0, |w| write(w, fast));
                            assert_eq!(
                                &got[..n],
                                &want[..m],
                                "{round} {first} {name:?} {number:?} {room} {fast}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A key and a string in one piece: what the key and [`W::json_str`] write.
#[test]
fn json_key_str_writes_what_each_piece_writes() {
    let keys: [&[u8]; 3] = [b",\"unit\":", b",\"a_rather_long_column_key\":", b""];
    let texts = [
        "",
        "us",
        "q\"",
        "t\tab",
        "sixteen_bytes_xx",
        "seventeen_bytes_x",
        "caf\u{e9}",
    ];
    for key in keys {
        for s in texts {
            for room in [4, 20, 60, 200] {
                let mut fast = vec![0; room];
                let n = write_line(&mut fast, 0, |w| w.json_key_str(key, s));
                let mut slow = vec![0; room];
                let m = write_line(&mut slow, 0, |w| {
                    w.put(key);
                    w.json_str(s);
                });
                assert_eq!(&fast[..n], &slow[..m], "{s:?} {room}");
            }
        }
    }
}

#[test]
fn copies_every_length_up_to_the_call() {
    let src: Vec<u8> = (0..=255u8).collect();
    for n in 0..=140 {
        let mut dst = vec![0u8; 160];
        copy(&mut dst, &src[7..7 + n]);
        assert_eq!(&dst[..n], &src[7..7 + n], "{n} bytes");
        assert!(dst[n..].iter().all(|&b| b == 0), "{n} bytes: nothing after");
    }
}

#[test]
fn copies_every_length_and_grows() {
    let mut buf = vec![0; ROOM];
    let src: Vec<u8> = (0..=255u8).cycle().take(3000).collect();
    let mut expected = Vec::new();
    for n in 0..70 {
        expected.extend_from_slice(&src[n..n * 2]);
    }
    expected.extend_from_slice(&src);
    expected.extend_from_slice(&[b' '; 150]);
    let mut tries = 0;
    let len = write_line(&mut buf, 0, |w| {
        tries += 1;
        for n in 0..70 {
            w.put(&src[n..n * 2]);
        }
        w.put(&src);
        w.spaces(150);
    });
    assert_eq!(&buf[..len], &expected[..]);
    // 5565 bytes: 1024 bytes of room at first, then 2048, 4096, 8192 (kept for the next
    // line).
    assert_eq!(tries, 4);
    assert_eq!(buf.len(), 8192);
    // After 5565 bytes kept, a line in the rest of the room.
    let n = write_line(&mut buf, len, |w| w.put(b"x"));
    assert_eq!(&buf[len..len + n], b"x");
}

/// A CSV field as the csv crate writes it (`QuoteStyle::Necessary`), whether written by
/// [`W::csv`] or in place and quoted afterwards by [`W::csv_fix`] (in the line, or moved one
/// byte on when it holds no quote), in every room the line starts with; `csv_fix` keeps the
/// field's text for the marks.
#[test]
fn csv_fields_as_the_csv_crate_writes_them() {
    let fields: [&[u8]; 9] = [
        b"plain",
        b"",
        b"84 (132, -124)",
        b"a,\"b\"",
        b"\"",
        b"line\nbreak",
        b"cr\r",
        b"framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), forced",
        b",",
    ];
    for field in fields {
        let mut want = Vec::new();
        {
            let mut wr = csv::WriterBuilder::new().from_writer(&mut want);
            wr.write_record([field, b"x"]).unwrap();
        }
        let want = &want[..want.len() - 3];
        for room in 0..100 {
            let mut buf = vec![0; room];
            let len = write_line(&mut buf, 0, |w| {
                w.byte(b'|');
                w.csv(field);
                w.byte(b'|');
            });
            assert_eq!(&buf[1..len - 1], want, "{field:?} in {room}");
            let mut buf = vec![0; room];
            let mut scratch = Vec::new();
            let mut kept = None;
            let len = write_line(&mut buf, 0, |w| {
                w.byte(b'|');
                let at = w.len();
                w.put(field);
                kept = w.csv_fix(at, &mut scratch);
                w.byte(b'|');
            });
            assert_eq!(&buf[1..len - 1], want, "{field:?} in {room}");
            match kept {
                Some((at, n)) => {
                    assert_eq!((at, &scratch[..n as usize]), (1, field), "{room}")
                }
                None => assert_eq!(want, field),
            }
        }
    }
}

#[test]
fn fields_as_the_byte_rules_write_them() {
    let mut buf = vec![0; 4];
    let len = write_line(&mut buf, 0, |w| {
        w.tsv(b"a\tb\nc");
        w.byte(b'|');
        w.csv(b"plain");
        w.byte(b'|');
        w.csv(b"a,\"b\"");
        w.byte(b'|');
        w.csv(b"tab\tonly");
        w.byte(b'|');
        w.json_str("q\"\\\n\x01 \u{e9}");
        w.byte(b'|');
        w.json_str("");
        w.byte(b'|');
        w.dec(0);
        w.byte(b' ');
        w.dec(u64::MAX);
    });
    assert_eq!(
        std::str::from_utf8(&buf[..len]).unwrap(),
        "a b c|plain|\"a,\"\"b\"\"\"|tab\tonly|\"q\\\"\\\\\\n\\u0001 \u{e9}\"|null|0 18446744073709551615"
    );
}
