//! The tests of `hex` (a file of their own: the module stays short).

use super::*;
use std::collections::BTreeMap;

/// A parsed record line: (type, offset, data), the checksum checked.
fn parse_line(text: &str) -> (u8, u16, Vec<u8>) {
    let body = text.strip_prefix(':').expect("a record starts with ':'");
    assert!(body.len().is_multiple_of(2), "odd record length: {text}");
    let bytes: Vec<u8> = (0..body.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&body[i..i + 2], 16).expect("hex digits"))
        .collect();
    assert_eq!(
        bytes.iter().fold(0u8, |sum, b| sum.wrapping_add(*b)),
        0,
        "checksum of {text}"
    );
    assert_eq!(usize::from(bytes[0]) + 5, bytes.len(), "count of {text}");
    let data = bytes[4..bytes.len() - 1].to_vec();
    (bytes[3], u16::from_be_bytes([bytes[1], bytes[2]]), data)
}

/// Reads a universal hex back as the spec defines it: each section's
/// data, by block type (independent of how `section` writes it).
fn separate(text: &str) -> BTreeMap<u16, Image> {
    let mut boards: BTreeMap<u16, Image> = BTreeMap::new();
    let (mut board, mut upper) = (None, 0u32);
    let mut ended = false;
    for record in text.lines() {
        assert!(!ended, "a record after End Of File: {record}");
        let (kind, offset, data) = parse_line(record);
        match kind {
            EXTENDED_LINEAR_ADDRESS => {
                upper = u32::from(u16::from_be_bytes([data[0], data[1]])) << 16
            }
            BLOCK_START => board = Some(u16::from_be_bytes([data[0], data[1]])),
            DATA | CUSTOM_DATA => {
                let board = board.expect("data inside a section");
                assert_eq!(kind == DATA, board == BOARD_V1, "data type of {record}");
                boards
                    .entry(board)
                    .or_default()
                    .add(upper | u32::from(offset), &data)
                    .expect("no overlap");
            }
            BLOCK_END => board = None,
            PADDED_DATA => {}
            END_OF_FILE => ended = true,
            other => panic!("unexpected record type {other:#04x}: {record}"),
        }
    }
    assert!(ended, "no End Of File record");
    boards
}

fn image(runs: &[(u32, &[u8])]) -> Image {
    let mut image = Image::default();
    for (address, bytes) in runs {
        image.add(*address, bytes).expect("disjoint runs");
    }
    image
}

/// `n` bytes that differ from their neighbours (so a shifted copy fails).
fn bytes(n: usize, seed: u8) -> Vec<u8> {
    (0..n)
        .map(|i| (i as u8).wrapping_mul(7).wrapping_add(seed))
        .collect()
}

#[test]
fn runs_join_and_overlaps_are_refused() {
    let mut image = image(&[(0x100, &[1, 2]), (0x104, &[5])]);
    image.add(0x102, &[3, 4]).unwrap();
    assert_eq!(image.runs(), [(0x100, vec![1, 2, 3, 4, 5])]);
    let error = image.add(0x0FF, &[9, 9]).unwrap_err();
    assert!(error.contains("0x000000ff"), "{error}");
    assert!(image.add(0x104, &[9]).is_err());
    assert!(image.add(0xFFFF_FFFF, &[1, 2]).is_err());
    image.add(0x200, &[7]).unwrap();
    assert_eq!(image.len(), 6);
    let (base, flat) = image.flat();
    assert_eq!(base, 0x100);
    assert_eq!(flat.len(), 0x101);
    assert_eq!(&flat[..5], &[1, 2, 3, 4, 5]);
    assert!(flat[5..0x100].iter().all(|&b| b == 0));
    assert_eq!(flat[0x100], 7);
}

#[test]
fn sections_load_where_their_segment_is_loaded() {
    let text = bytes(0x40, 1);
    let data = bytes(0x10, 99);
    // .text runs where it loads; .data runs in RAM and loads after .text.
    let segments = [
        Segment {
            offset: 0x1000,
            vaddr: 0,
            paddr: 0,
            filesz: 0x40,
        },
        Segment {
            offset: 0x2000,
            vaddr: 0x2000_0000,
            paddr: 0x40,
            filesz: 0x10,
        },
    ];
    let sections = [
        Section {
            name: ".text",
            offset: 0x1000,
            data: &text,
        },
        Section {
            name: ".data",
            offset: 0x2000,
            data: &data,
        },
    ];
    let image = image_of(&sections, &segments).unwrap();
    let mut expected = text.clone();
    expected.extend_from_slice(&data);
    assert_eq!(image.runs(), [(0, expected)]);
    let stray = Section {
        name: ".stray",
        offset: 0x3000,
        data: &data,
    };
    let error = image_of(&[stray], &segments).unwrap_err();
    assert!(
        error.contains(".stray") && error.contains("0x3000"),
        "{error}"
    );
}

#[test]
fn plain_hex_reads_back_as_the_image_across_64k() {
    let low = bytes(40, 3);
    let across = bytes(100, 11);
    let image = image(&[(0x10, &low), (0x1_FFD0, &across)]);
    let text = intel_hex(&image).unwrap();
    assert_eq!(image_of_intel_hex(&text), Ok(image));
    let lines = ihex::Reader::new(&text)
        .map(|record| match record.expect("a valid record") {
            ihex::Record::Data { value, .. } => assert!(value.len() <= PLAIN_RECORD),
            ihex::Record::ExtendedLinearAddress(_) | ihex::Record::EndOfFile => {}
            other => panic!("unexpected {other:?}"),
        })
        .count();
    // Three address records (0x0000, 0x0001, 0x0002): the 100 bytes cross 0x20000.
    assert_eq!(text.matches(":02000004").count(), 3);
    assert!(text.starts_with(":020000040000FA\n"));
    assert!(text.ends_with(":00000001FF\n"));
    assert_eq!(lines, text.lines().count());
}

#[test]
fn reading_plain_hex() {
    // Segment addresses (×16) as well as linear ones (×65 536).
    let text = ":020000021000EC\n:0100040042B9\n:020000040002F8\n:020000000102FB\n:00000001FF\n";
    assert_eq!(
        image_of_intel_hex(text),
        Ok(image(&[(0x1_0004, &[0x42]), (0x2_0000, &[1, 2])]))
    );
    let bad = text.replace("0042B9", "0042B8");
    let error = image_of_intel_hex(&bad).unwrap_err();
    assert!(error.starts_with("record 2:"), "{error}");
    assert!(
        image_of_intel_hex(":0100040042B9\n").is_err(),
        "no End Of File"
    );
    let twice = ":0100040042B9\n:0100040042B9\n:00000001FF\n";
    assert!(image_of_intel_hex(twice).unwrap_err().contains("record 2"));
}

#[test]
fn our_record_lines_are_the_crates() {
    let record = ihex::Record::Data {
        offset: 0x1234,
        value: bytes(32, 5),
    };
    assert_eq!(
        line(DATA, 0x1234, &bytes(32, 5)),
        record.to_record_string().unwrap() + "\n"
    );
    assert_eq!(
        line(EXTENDED_LINEAR_ADDRESS, 0, &[0x10, 0x00]),
        ihex::Record::ExtendedLinearAddress(0x1000)
            .to_record_string()
            .unwrap()
            + "\n"
    );
    // The spec's own example lines (spec/index.md, "Example").
    assert_eq!(
        line(BLOCK_START, 0, &[0x99, 0x00, 0xC0, 0xDE]),
        ":0400000A9900C0DEBB\n"
    );
    assert_eq!(line(BLOCK_END, 0, &[]), ":0000000BF5\n");
    assert_eq!(
        line(
            CUSTOM_DATA,
            0x1014,
            &[0x00, 0x80, 0x07, 0x00, 0x00, 0xE0, 0x07, 0x00]
        ),
        ":0810140D0080070000E0070059\n"
    );
}

#[test]
fn universal_sections_are_aligned_and_separate_into_the_images() {
    // Sizes around a block's worth of records, a run across 64 KiB, a
    // high address (the nRF's UICR).
    for (v1_len, v2_len) in [(1, 1), (200, 333), (4096, 17), (12_345, 70_000)] {
        let v1 = image(&[(0, &bytes(v1_len, 1)), (0x3_F000, &bytes(20, 2))]);
        let v2 = image(&[(0, &bytes(v2_len, 3)), (0x1000_1014, &bytes(8, 4))]);
        let text = universal_hex(&v1, &v2);
        assert!(text.is_ascii() && !text.contains('\r'));
        let back = separate(&text);
        assert_eq!(back.len(), 2, "{v1_len}/{v2_len}: two boards");
        assert_eq!(back[&BOARD_V1], v1, "{v1_len}/{v2_len}: V1");
        assert_eq!(back[&BOARD_V2], v2, "{v1_len}/{v2_len}: V2");
        // Each section: ELA, Block Start at a block boundary; Block End
        // right before the next boundary.
        let mut offset = 0;
        let mut starts = Vec::new();
        let lines: Vec<&str> = text.lines().collect();
        for (i, record) in lines.iter().enumerate() {
            let (kind, _, data) = parse_line(record);
            assert!(data.len() <= UNIVERSAL_RECORD, "{record}");
            if kind == BLOCK_START {
                let ela = lines[i - 1];
                let at = offset - ela.len() - 1;
                assert_eq!(at % BLOCK, 0, "section at {at}");
                assert_eq!(parse_line(ela).0, EXTENDED_LINEAR_ADDRESS);
                starts.push((at, u16::from_be_bytes([data[0], data[1]])));
                assert_eq!(data.len(), 4);
            }
            offset += record.len() + 1;
            if kind == BLOCK_END {
                assert_eq!(offset % BLOCK, 0, "a section ends at {offset}");
            }
        }
        assert_eq!(starts[0], (0, BOARD_V1));
        assert_eq!(starts[1].1, BOARD_V2);
        assert!(text.ends_with(":00000001FF\n"));
        assert_eq!(text.matches(":00000001FF").count(), 1);
    }
}

#[test]
fn every_gap_to_a_boundary_is_filled() {
    // Data lengths 1..=64 move the section's end through every even
    // remainder modulo 512.
    let mut remainders = std::collections::BTreeSet::new();
    for n in 1..=300 {
        let v1 = image(&[(0, &bytes(n, 9))]);
        let mut out = String::new();
        section(&mut out, BOARD_V1, &v1);
        assert_eq!(out.len() % BLOCK, 0, "{n} bytes");
        let body: usize = out
            .lines()
            .filter(|l| !matches!(parse_line(l).0, PADDED_DATA | BLOCK_END))
            .map(|l| l.len() + 1)
            .sum();
        remainders.insert(body % BLOCK);
    }
    assert!(remainders.len() > 100, "{} remainders", remainders.len());
}
