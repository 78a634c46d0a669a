//! The tests of `universal_hex` (a file of their own: the module stays short).

use super::*;
use std::collections::BTreeMap;

/// A section of `block` holding `runs` (address, bytes), written with
/// `data_kind` records of up to 16 bytes (not the 32 the patch writes),
/// padded to the boundary: the input.
fn section(out: &mut Out, block: u16, data_kind: u8, runs: &[(u32, Vec<u8>)]) {
    let start = out.len;
    let mut upper = runs.first().map_or(0, |r| r.0 >> 16);
    out.line(EXTENDED_LINEAR_ADDRESS, 0, &(upper as u16).to_be_bytes())
        .unwrap();
    let [high, low] = block.to_be_bytes();
    out.line(BLOCK_START, 0, &[high, low, 0xC0, 0xDE]).unwrap();
    for (at, bytes) in runs {
        for (i, chunk) in bytes.chunks(16).enumerate() {
            let address = at + 16 * i as u32;
            if address >> 16 != upper {
                upper = address >> 16;
                out.line(EXTENDED_LINEAR_ADDRESS, 0, &(upper as u16).to_be_bytes())
                    .unwrap();
            }
            out.line(data_kind, address as u16, chunk).unwrap();
        }
    }
    close(out, start).unwrap();
}

/// Runs of bytes: (address, bytes).
type Runs = Vec<(u32, Vec<u8>)>;

fn universal(sections: &[(u16, u8, Runs)]) -> Vec<u8> {
    let mut buf = vec![0; 1 << 20];
    let mut out = Out {
        buf: &mut buf,
        len: 0,
    };
    for (block, kind, runs) in sections {
        section(&mut out, *block, *kind, runs);
    }
    out.line(END_OF_FILE, 0, &[]).unwrap();
    let len = out.len;
    buf.truncate(len);
    buf
}

/// Each section's bytes by block type, and its data record type, read as
/// the spec defines them (not as `patch` goes); every section starts and
/// ends on a 512-byte boundary.
fn separate(text: &[u8]) -> BTreeMap<u16, (u8, BTreeMap<u32, u8>)> {
    let text = std::str::from_utf8(text).unwrap();
    let mut boards: BTreeMap<u16, (u8, BTreeMap<u32, u8>)> = BTreeMap::new();
    let (mut board, mut upper, mut at) = (None, 0u32, 0usize);
    for (n, line) in text.lines().enumerate() {
        let record = parse(line.as_bytes(), n + 1).unwrap();
        let data = record.data();
        match record.kind {
            EXTENDED_LINEAR_ADDRESS => {
                upper = u32::from(u16::from_be_bytes([data[0], data[1]])) << 16
            }
            BLOCK_START => {
                assert_eq!((at - line_len(2)) % BLOCK, 0, "section at {at}");
                board = Some(u16::from_be_bytes([data[0], data[1]]));
            }
            DATA | CUSTOM_DATA => {
                let entry = boards.entry(board.unwrap()).or_default();
                entry.0 = record.kind;
                for (i, b) in data.iter().enumerate() {
                    let address = upper + u32::from(record.offset) + i as u32;
                    assert!(entry.1.insert(address, *b).is_none(), "{address:#x} twice");
                }
            }
            BLOCK_END => {
                assert_eq!(
                    (at + line.len() + 1) % BLOCK,
                    0,
                    "a section ends at line {n}"
                );
                board = None;
            }
            _ => {}
        }
        assert!(line.len() <= line_len(RECORD), "{line}");
        at += line.len() + 1;
    }
    boards
}

fn bytes(n: usize, seed: u8) -> Vec<u8> {
    (0..n)
        .map(|i| (i as u8).wrapping_mul(7).wrapping_add(seed))
        .collect()
}

fn flat(runs: &[(u32, Vec<u8>)]) -> BTreeMap<u32, u8> {
    runs.iter()
        .flat_map(|(at, b)| b.iter().enumerate().map(move |(i, b)| (at + i as u32, *b)))
        .collect()
}

#[test]
fn the_region_lands_in_each_board_and_the_rest_stays() {
    let v1_region = 0x3_F000..0x4_0000;
    let v2_region = 0x7_B000..0x7_C000;
    // V1: code across 64 KiB, an old region's bytes from below its start
    // and up to its end, the UICR above it. V2: old region bytes across
    // its end, data after the region in its 64 KiB.
    let v1 = vec![
        (0, bytes(0x1_2345, 1)),
        (0x3_EFF0, bytes(0x30, 2)),
        (0x3_FFF8, bytes(8, 3)),
        (0x1000_1014, bytes(8, 4)),
    ];
    let v2 = vec![
        (0, bytes(0x9876, 5)),
        (0x7_BFF8, bytes(0x20, 10)),
        (0x7_C100, bytes(40, 6)),
    ];
    let other = vec![(0x100, bytes(77, 7))];
    let hex = universal(&[
        (BOARD_V1, DATA, v1.clone()),
        (0x9904, CUSTOM_DATA, other.clone()),
        (BOARD_V2, CUSTOM_DATA, v2.clone()),
    ]);
    let region = bytes(1000, 8);
    let patches = [
        Patch {
            block: BOARD_V1,
            region: v1_region.clone(),
            bytes: &region,
        },
        Patch {
            block: BOARD_V2,
            region: v2_region.clone(),
            bytes: &region,
        },
    ];
    let mut out = vec![0; 1 << 20];
    let len = patch(&hex, &patches, &mut out).unwrap();
    let boards = separate(&out[..len]);
    for (block, kind, runs, range) in [
        (BOARD_V1, DATA, &v1, v1_region),
        (BOARD_V2, CUSTOM_DATA, &v2, v2_region),
    ] {
        let mut expected = flat(runs);
        expected.retain(|at, _| !range.contains(at));
        expected.extend(flat(&[(range.start, region.clone())]));
        assert_eq!(boards[&block].0, kind, "{block:04X}'s data records");
        let got = &boards[&block].1;
        let diff: Vec<_> = expected
            .iter()
            .filter(|(at, b)| got.get(at) != Some(b))
            .map(|(at, _)| *at)
            .chain(got.keys().filter(|at| !expected.contains_key(at)).copied())
            .take(4)
            .collect();
        assert!(diff.is_empty(), "{block:04X}'s image differs at {diff:x?}");
    }
    assert!(
        boards[&0x9904].1 == flat(&other),
        "a foreign board as it was"
    );
    // Patched again (the served hex may carry a region): the new region alone.
    let again = bytes(20, 9);
    let patches = patches.map(|p| Patch { bytes: &again, ..p });
    let mut twice = vec![0; 1 << 20];
    let len2 = patch(&out[..len], &patches, &mut twice).unwrap();
    let boards = separate(&twice[..len2]);
    assert_eq!(boards[&BOARD_V2].1.get(&0x7_B000), Some(&again[0]));
    assert_eq!(boards[&BOARD_V2].1.get(&0x7_B014), None);
    assert!(std::str::from_utf8(&twice[..len2])
        .unwrap()
        .ends_with(":00000001FF\n"));
}

#[test]
fn every_gap_to_a_boundary_is_filled() {
    // Region lengths move the section's end through every remainder.
    let hex = universal(&[(BOARD_V1, DATA, vec![(0, bytes(100, 1))])]);
    for n in 1..=300 {
        let region = bytes(n, 2);
        let patches = [Patch {
            block: BOARD_V1,
            region: 0x3_F000..0x4_0000,
            bytes: &region,
        }];
        let mut out = vec![0; 1 << 16];
        let len = patch(&hex, &patches, &mut out).unwrap();
        let boards = separate(&out[..len]);
        assert_eq!(boards[&BOARD_V1].1.len(), 100 + n);
    }
}

#[test]
fn errors_name_the_line_and_what() {
    let hex = universal(&[(BOARD_V1, DATA, vec![(0, bytes(100, 1))])]);
    let region = [1, 2, 3];
    let v1 = Patch {
        block: BOARD_V1,
        region: 0x3_F000..0x4_0000,
        bytes: &region,
    };
    let v2 = Patch {
        block: BOARD_V2,
        ..v1.clone()
    };
    let mut out = vec![0; 1 << 16];
    let text = std::str::from_utf8(&hex).unwrap();
    let error = |text: &str, patches: &[Patch], out: &mut [u8]| {
        patch(text.as_bytes(), patches, out)
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        error(text, &[v1.clone(), v2], &mut out),
        "no section of block type 9903"
    );
    // The third line's last digit changed: its checksum no longer adds up.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let third = lines[2].pop().unwrap();
    lines[2].push(if third == '0' { '1' } else { '0' });
    assert_eq!(
        error(&lines.join("\n"), std::slice::from_ref(&v1), &mut out),
        "line 3: wrong checksum"
    );
    assert_eq!(
        error("hello\n", std::slice::from_ref(&v1), &mut out),
        "line 1: does not start with ':'"
    );
    assert_eq!(
        error(
            ":00000001FF\n:00000001FF\n",
            std::slice::from_ref(&v1),
            &mut out
        ),
        "line 2: a record after End Of File"
    );
    assert_eq!(
        error(":0100000042BD\n", std::slice::from_ref(&v1), &mut out),
        "line 1: a data record outside a section"
    );
    assert_eq!(
        error(
            text.trim_end_matches(":00000001FF\n"),
            std::slice::from_ref(&v1),
            &mut out
        ),
        "no End Of File record"
    );
    assert_eq!(
        error(text, &[v1], &mut out[..300]),
        "the result is over 300 bytes"
    );
}
