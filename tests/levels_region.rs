//! The levels region (`board::levels_region`): what `cargo xtask hex --level`
//! writes into flash and what a board reads back, or refuses with a reason.

use marble_rolling::board::levels_region::{
    at_boot, crc32, level, read, write, LevelCheck, Region, RegionError, WriteError, HEADER, MAGIC,
    MAX_LEVELS, SIZE, VERSION,
};
use marble_rolling::board::microbit_v1;
use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::endless::{Endless, MazeSlot, Seeds, Stage, StageError};
use marble_rolling::game::level::{parse, LevelErrorKind, LevelView};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{GameConfig, Phase, DEFAULT_EVENTS};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::physics::Fx;
use proptest::prelude::*;

const CORNER: &str = "name: my-corner
time_limit_s: 30
---
#########
#S......#
#######.#
#G......#
#########
";

const TWO_STOREYS: &str = "name: down
---
#######
#S.O..#
#######
===
#######
#..G..#
#######
";

/// A region of `texts` in a buffer of [`SIZE`] bytes.
fn region(texts: &[&str]) -> (Vec<u8>, usize) {
    let mut flash = vec![0u8; SIZE];
    let bytes: Vec<&[u8]> = texts.iter().map(|t| t.as_bytes()).collect();
    let used = write(&bytes, &mut flash).expect("fits");
    (flash, used)
}

/// The region's CRC made right again after a deliberate edit.
fn reseal(flash: &mut [u8]) {
    let length = u32::from_le_bytes(flash[12..16].try_into().unwrap()) as usize;
    let crc = crc32(&flash[8..HEADER + length]);
    flash[4..8].copy_from_slice(&crc.to_le_bytes());
}

fn texts(region: Region) -> Vec<String> {
    (0..region.len())
        .map(|i| String::from_utf8(region.bytes(i).expect("entry").to_vec()).unwrap())
        .collect()
}

#[test]
fn the_crc_is_zlibs() {
    // The CRC-32 check value (IEEE 802.3 / zlib) of the nine ASCII digits.
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
}

#[test]
fn a_good_region_gives_back_its_levels() {
    let (flash, used) = region(&[CORNER, TWO_STOREYS]);
    assert_eq!(used, HEADER + 2 + CORNER.len() + 2 + TWO_STOREYS.len());
    assert_eq!(&flash[..4], &MAGIC);
    assert_eq!(flash[8], VERSION);
    assert!(flash[used..].iter().all(|&b| b == 0xFF), "erased after it");
    let region = read(&flash).expect("a good region");
    assert_eq!(region.len(), 2);
    assert_eq!(texts(region), [CORNER, TWO_STOREYS]);
    assert_eq!(region.bytes(2), None);
    let corner = level::<64>(region.bytes(0).unwrap()).expect("parses");
    assert_eq!(corner.info.name, "my-corner");
    assert_eq!(corner.info.time_limit_s, 30);
    let down = level::<64>(region.bytes(1).unwrap()).expect("parses");
    assert_eq!(down.info.storeys, 2);
    // Only the used bytes are read: the same region in a shorter slice.
    assert_eq!(read(&flash[..used]), Ok(region));
}

#[test]
fn erased_flash_and_foreign_bytes_are_not_a_region() {
    assert_eq!(read(&[0xFF; SIZE]), Err(RegionError::Erased));
    assert_eq!(read(&[]), Err(RegionError::Erased));
    assert_eq!(read(&[0u8; SIZE]), Err(RegionError::Magic([0, 0, 0, 0])));
    let (mut flash, _) = region(&[CORNER]);
    flash[8] = VERSION + 1;
    reseal(&mut flash);
    assert_eq!(read(&flash), Err(RegionError::Version(VERSION + 1)));
    for count in [0u8, MAX_LEVELS as u8 + 1] {
        let (mut flash, _) = region(&[CORNER]);
        flash[9] = count;
        reseal(&mut flash);
        assert_eq!(read(&flash), Err(RegionError::Count(count)));
    }
}

#[test]
fn every_flipped_bit_after_the_magic_fails_the_crc() {
    let (flash, used) = region(&[CORNER, TWO_STOREYS]);
    for at in 4..used {
        for bit in 0..8 {
            let mut bad = flash.clone();
            bad[at] ^= 1 << bit;
            match read(&bad) {
                Err(RegionError::Crc { stored, computed }) => assert_ne!(stored, computed),
                // A flip in the length's high bits puts it past the region,
                // which is checked before the CRC.
                Err(RegionError::Length { .. }) if (12..16).contains(&at) => {}
                other => panic!("bit {bit} of byte {at} flipped: {other:?}"),
            }
        }
    }
}

#[test]
fn a_truncated_region_is_refused() {
    let (flash, used) = region(&[CORNER, TWO_STOREYS]);
    // Cut short anywhere: never read as a region, never a panic.
    for cut in 0..used {
        let result = read(&flash[..cut]);
        assert!(result.is_err(), "cut at {cut}: {result:?}");
        if cut >= HEADER {
            assert_eq!(
                result,
                Err(RegionError::Length {
                    length: (used - HEADER) as u32,
                    room: cut - HEADER
                }),
                "cut at {cut}"
            );
        }
    }
    // A header that promises a third level the bytes do not hold.
    let (mut flash, _) = region(&[CORNER, TWO_STOREYS]);
    flash[9] = 3;
    reseal(&mut flash);
    assert_eq!(read(&flash), Err(RegionError::Truncated { index: 2 }));
    // An entry longer than what is left.
    let (mut flash, _) = region(&[CORNER, TWO_STOREYS]);
    let second = HEADER + 2 + CORNER.len();
    flash[second..second + 2].copy_from_slice(&(TWO_STOREYS.len() as u16 + 1).to_le_bytes());
    reseal(&mut flash);
    assert_eq!(read(&flash), Err(RegionError::Truncated { index: 1 }));
    // Bytes after the last entry.
    let (mut flash, used) = region(&[CORNER]);
    flash[12..16].copy_from_slice(&((used - HEADER + 3) as u32).to_le_bytes());
    flash[used..used + 3].fill(0);
    reseal(&mut flash);
    assert_eq!(read(&flash), Err(RegionError::Trailing { bytes: 3 }));
}

#[test]
fn a_level_the_board_cannot_show() {
    // 31 × 31 tiles, one storey: 31 · 2 · 31 = 1922 bits, 61 words.
    let mut big = String::from("name: big\n---\n");
    for k in 0..31 {
        let row: String = (0..31)
            .map(|i| match (i, k) {
                (1, 1) => 'S',
                (29, 29) => 'G',
                (0 | 30, _) | (_, 0 | 30) => '#',
                _ => '.',
            })
            .collect();
        big.push_str(&row);
        big.push('\n');
    }
    let (flash, _) = region(&[&big]);
    let region = read(&flash).expect("the region is sound");
    let text = region.bytes(0).unwrap();
    assert!(level::<61>(text).is_ok(), "fits in 61 words");
    match level::<32>(text) {
        Err(LevelCheck::TooLarge { needs, room }) => assert_eq!((needs, room), (61, 32)),
        other => panic!("not too large: {other:?}"),
    }
    // Past the format's own limit it is the parser's error, not the board's.
    let wide = format!("---\n{}\n", "#".repeat(129));
    assert!(matches!(
        level::<32>(wide.as_bytes()),
        Err(LevelCheck::Parse(e)) if e.kind == LevelErrorKind::TooLarge
    ));
}

#[test]
fn a_bad_level_has_the_error_sim_check_gives() {
    let bad = CORNER.replace("#S......#", "#S..x...#");
    let expected = parse::<64>(&bad).unwrap_err();
    assert_eq!((expected.line, expected.column), (5, 5));
    assert_eq!(
        level::<64>(bad.as_bytes()).unwrap_err(),
        LevelCheck::Parse(expected)
    );
    let mut not_utf8 = CORNER.as_bytes().to_vec();
    not_utf8[20] = 0xC3;
    not_utf8[21] = b'x';
    assert!(matches!(
        level::<64>(&not_utf8),
        Err(LevelCheck::Parse(e)) if matches!(e.kind, LevelErrorKind::NotUtf8 { byte: 0xC3 })
    ));
}

#[test]
fn the_largest_region() {
    // MAX_LEVELS levels whose long names fill the region to its last byte.
    let base = CORNER.replace("name: my-corner", "name: ");
    let per_level = (SIZE - HEADER) / MAX_LEVELS - 2;
    let mut levels: Vec<String> = (0..MAX_LEVELS)
        .map(|i| {
            let name = format!("l{i}-{}", "x".repeat(per_level - base.len() - 3));
            base.replace("name: ", &format!("name: {name}"))
        })
        .collect();
    let used: usize = HEADER + levels.iter().map(|l| 2 + l.len()).sum::<usize>();
    assert!(used <= SIZE);
    let last = levels.last_mut().unwrap();
    last.insert_str(last.find('\n').unwrap(), &"y".repeat(SIZE - used));
    let refs: Vec<&str> = levels.iter().map(String::as_str).collect();
    let (flash, used) = region(&refs);
    assert_eq!(used, SIZE, "the region is full");
    let region = read(&flash).expect("the largest region reads");
    assert_eq!(texts(region), levels);
    for i in 0..MAX_LEVELS {
        assert!(level::<64>(region.bytes(i).unwrap()).is_ok(), "level {i}");
    }
    // One byte more does not fit; nor does a ninth level.
    let mut over: Vec<&[u8]> = refs.iter().map(|t| t.as_bytes()).collect();
    let longer = format!("{}z", levels[0]);
    over[0] = longer.as_bytes();
    let mut out = vec![0u8; SIZE];
    assert_eq!(
        write(&over, &mut out),
        Err(WriteError::TooBig {
            needs: SIZE + 1,
            room: SIZE
        })
    );
    let nine = vec![CORNER.as_bytes(); MAX_LEVELS + 1];
    assert_eq!(write(&nine, &mut out), Err(WriteError::Count(9)));
    assert_eq!(write(&[], &mut out), Err(WriteError::Count(0)));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any bytes, a region's head or not: an answer, never a panic, and a
    /// region read is one whose entries can all be taken.
    #[test]
    fn any_bytes_are_answered(mut bytes in proptest::collection::vec(any::<u8>(), 0..256), magic in any::<bool>()) {
        // Half the cases get a sound header over random entries, so that
        // the entries' framing is what is tried.
        if magic && bytes.len() >= HEADER {
            bytes[..4].copy_from_slice(&MAGIC);
            bytes[8] = VERSION;
            bytes[9] = bytes[9] % (MAX_LEVELS as u8) + 1;
            let length = (bytes.len() - HEADER) as u32;
            bytes[12..16].copy_from_slice(&length.to_le_bytes());
            reseal(&mut bytes);
        }
        if let Ok(region) = read(&bytes) {
            for i in 0..region.len() {
                let text = region.bytes(i).expect("every entry");
                let _ = level::<8>(text);
            }
        }
    }
}

// ---------------------------------------------------------------------------
// The region on a board: read at boot (`at_boot`), its levels played first in
// the run (`Endless::level`), as `app::game_task` and the demo take them.
// ---------------------------------------------------------------------------

/// The micro:bit v1's slot, the smallest board's: what a region level must fit.
type V1Slot =
    MazeSlot<{ microbit_v1::MAZE_REACH.words() }, { microbit_v1::MAZE_REACH.text_bytes() }>;

/// `flash` for the life of the test run, as the board's flash is.
fn flash_of(bytes: &[u8]) -> &'static [u8] {
    Box::leak(bytes.to_vec().into_boxed_slice())
}

/// The v1's run from the region bytes `flash`, and its first `n` levels as
/// the game task takes them: each one's name, or why it is not played.
fn v1_run(flash: &[u8], n: usize) -> (Endless, Vec<Result<String, StageError<'static>>>) {
    let region = at_boot(flash_of(flash));
    let mut slot = V1Slot::new(microbit_v1::MAZE_REACH).with_region(region);
    let endless = Endless::new(slot.region(), microbit_v1::MAZE_REACH, Seeds::Count);
    let levels = (0..n)
        .map(|number| {
            endless
                .level(number, &mut slot)
                .map(|level| level.info.name.to_string())
        })
        .collect();
    (endless, levels)
}

/// The built-in levels' names, as the run after the region has them.
fn builtins(n: usize) -> Vec<Result<String, StageError<'static>>> {
    LEVELS[..n]
        .iter()
        .map(|level| Ok(level.info.name.to_string()))
        .collect()
}

/// The autopilot's run on `level`, as the demo and `cargo sim --autopilot`
/// play it: the outcome, the steps and the state hash.
fn autopilot_run(level: LevelView<'_>) -> (Phase, u64, u64) {
    let config = GameConfig::stepped_by(DEFAULT_EVENTS);
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).expect("sets up");
    let mut pilot = Autopilot::new(&level);
    let limit = u64::from(level.info.time_limit_s) * u64::from(config.frame_hz()) + 10;
    for _ in 0..limit {
        if session.autopilot_frame(&mut pilot) != Phase::Playing {
            break;
        }
    }
    (
        session.game().phase(),
        session.game().steps(),
        session.state_hash(),
    )
}

#[test]
fn a_good_region_is_played_first_then_the_built_in_levels_and_the_same_mazes() {
    let other = CORNER.replace("my-corner", "my-other-corner");
    let (flash, _) = region(&[CORNER, &other]);
    let (endless, levels) = v1_run(&flash, 4);
    assert_eq!(endless.from_region, 2);
    let mut expected = vec![
        Ok("my-corner".to_string()),
        Ok("my-other-corner".to_string()),
    ];
    expected.extend(builtins(2));
    assert_eq!(levels, expected);
    assert_eq!(endless.stage(1), Stage::Region(1));
    assert_eq!(endless.stage(2), Stage::Builtin(0));
    // The best times stay the built-in levels' own.
    assert_eq!(endless.builtin(1), None);
    assert_eq!(endless.builtin(2), Some(0));
    // The mazes after them are the ones a board without a region plays.
    let plain = Endless::new(None, microbit_v1::MAZE_REACH, Seeds::Count);
    for k in 0..3 {
        assert_eq!(
            endless.maze(2 + LEVELS.len() + k),
            plain.maze(LEVELS.len() + k)
        );
    }
    // Parsed into the v1's slot, the level plays as the file does in `cargo
    // sim -- --level my-corner.level --autopilot`: the same steps and hash.
    let region = read(&flash).unwrap();
    let mut slot = V1Slot::new(microbit_v1::MAZE_REACH);
    let from_slot = autopilot_run(slot.load(region.bytes(0).unwrap()).expect("fits"));
    let file = parse::<64>(CORNER).expect("parses");
    let from_file = autopilot_run(file.view());
    assert_eq!(from_slot.0, Phase::Won);
    assert_eq!(from_slot, from_file);
}

#[test]
fn an_erased_region_is_no_levels() {
    let erased = [0xFFu8; SIZE];
    assert_eq!(at_boot(&erased), None);
    let (endless, levels) = v1_run(&erased, 2);
    assert_eq!(endless.from_region, 0);
    assert_eq!(levels, builtins(2));
    // QEMU's `microbit` machine reads unloaded flash as zeros: refused too.
    assert_eq!(at_boot(&[0u8; SIZE]), None);
}

#[test]
fn a_region_with_a_bad_crc_is_ignored() {
    let (mut flash, _) = region(&[CORNER]);
    // One tile of the level changed after the CRC was made.
    let at = HEADER + 2 + CORNER.find("#S").unwrap() + 2;
    flash[at] = b'#';
    assert!(matches!(read(&flash), Err(RegionError::Crc { .. })));
    let (endless, levels) = v1_run(&flash, 2);
    assert_eq!(endless.from_region, 0);
    assert_eq!(levels, builtins(2));
}

#[test]
fn a_truncated_region_is_ignored() {
    let (flash, used) = region(&[CORNER, TWO_STOREYS]);
    // The bytes end before the header's length: a region cut short.
    for cut in [used - 1, HEADER + 3, HEADER, 5] {
        assert_eq!(at_boot(&flash[..cut]), None, "cut at {cut}");
        let (endless, levels) = v1_run(&flash[..cut], 2);
        assert_eq!(endless.from_region, 0);
        assert_eq!(levels, builtins(2), "cut at {cut}");
    }
}

#[test]
fn a_level_the_board_cannot_hold_or_parse_is_skipped_alone() {
    // Wider than the v1's slot (one storey: two layers of side × side tiles).
    let room = microbit_v1::MAZE_REACH.words();
    let side = (1..).find(|s| 2 * s * s > 32 * room).unwrap();
    let mut wide = String::from("name: too-wide\n---\n");
    for k in 0..side {
        let row: String = (0..side)
            .map(|i| match (i, k) {
                (1, 1) => 'S',
                _ if (i, k) == (side - 2, side - 2) => 'G',
                _ if i == 0 || k == 0 || i == side - 1 || k == side - 1 => '#',
                _ => '.',
            })
            .collect();
        wide.push_str(&row);
        wide.push('\n');
    }
    assert!(
        parse::<256>(&wide).is_ok(),
        "a level the format allows, {side} tiles a side"
    );
    let bad = CORNER
        .replace("my-corner", "typo")
        .replace("#S......#", "#S..x...#");
    let (flash, _) = region(&[&wide, &bad, CORNER]);
    let (endless, levels) = v1_run(&flash, 4);
    assert_eq!(endless.from_region, 3);
    let Err(StageError::Skipped {
        index: 0,
        name: Some("too-wide"),
        why: LevelCheck::TooLarge { needs, room: r },
    }) = levels[0]
    else {
        panic!(
            "the wide level is not skipped as too large: {:?}",
            levels[0]
        );
    };
    assert!(
        needs > room && r == room,
        "needs {needs} of {r}, the slot {room}"
    );
    // The same error `cargo sim -- --check` gives, at its line and column.
    let expected = parse::<64>(&bad).unwrap_err();
    assert_eq!(
        levels[1],
        Err(StageError::Skipped {
            index: 1,
            name: Some("typo"),
            why: LevelCheck::Parse(expected)
        })
    );
    assert_eq!(
        levels[1].as_ref().unwrap_err().to_string(),
        format!("level 2 of the levels region (typo) is skipped: {expected}")
    );
    // The next one plays, then the built-in levels.
    assert_eq!(levels[2], Ok("my-corner".to_string()));
    assert_eq!(levels[3], builtins(1)[0]);
}
