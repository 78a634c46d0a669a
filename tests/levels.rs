//! The level format: built-ins, defaults, and errors with line and column.

use marble_rolling::game::level::{parse, words_needed, LevelError, LevelErrorKind};
use marble_rolling::game::levels::{by_name, LEVELS};
use marble_rolling::game::rules::{Game, GameConfig, Phase};

const W: usize = 1016;

fn error_at(src: &str) -> LevelError {
    parse::<W>(src).expect_err("should be rejected")
}

#[test]
fn eight_builtins_of_rising_size_use_every_effect() {
    assert!(LEVELS.len() >= 8);
    let mut any = [false; 5];
    for l in LEVELS.iter() {
        let e = l.info.spec.effects;
        for (slot, on) in
            any.iter_mut()
                .zip([e.rolling, e.friction, e.board_motion, e.holes, e.marbles])
        {
            *slot |= on;
        }
        assert!(
            Game::<fixed::types::I8F24>::new(*l, GameConfig::DEFAULT).is_ok(),
            "{}",
            l.info.name
        );
    }
    assert_eq!(
        any, [true; 5],
        "rolling, friction, board_motion, holes, marbles"
    );
    let sizes: Vec<usize> = LEVELS
        .iter()
        .map(|l| l.info.nx as usize * l.info.nz as usize)
        .collect();
    assert!(sizes.first() < sizes.last());
    assert_eq!(by_name("corner").map(|(i, _)| i), Some(1));
    assert!(by_name("nope").is_none());
}

#[test]
fn defaults_apply_when_the_header_is_empty() {
    let l = parse::<W>("---\n#####\n#S.G#\n#####\n").unwrap();
    assert_eq!(l.info.name, "untitled");
    assert_eq!(
        (
            l.info.spec.short_um,
            l.info.spec.long_um,
            l.info.spec.radius_um
        ),
        (2000, 10000, 3500)
    );
    assert_eq!(l.info.spec.restitution_milli, 500);
    assert_eq!(l.info.time_limit_s, 60);
    assert!(l.info.spec.effects.rolling && !l.info.spec.effects.friction);
    assert_eq!(l.info.starts(), &[(1, 1)]);
    assert_eq!(l.info.goals(), &[(3, 1)]);
    assert_eq!(words_needed("---\n#####\n#S.G#\n#####\n"), 1);
}

#[test]
fn header_values_are_read() {
    let src = "name: Test level\nshort_mm: 1.5\nlong_mm: 12\nmarble_radius_mm: 4.25\nrestitution: 0.75\n\
               effects: friction, board_motion\nrolling_resistance: 0.02\ntime_limit_s: 90\n---\n#####\n#S.G#\n#O###\n";
    let l = parse::<W>(src).unwrap();
    assert_eq!(l.info.name, "Test level");
    let s = l.info.spec;
    assert_eq!(
        (s.short_um, s.long_um, s.radius_um, s.restitution_milli),
        (1500, 12000, 4250, 750)
    );
    assert_eq!(s.rolling_resistance_ppm, 20_000);
    assert!(s.effects.friction && s.effects.board_motion && s.effects.holes && !s.effects.marbles);
    assert_eq!(l.info.time_limit_s, 90);
}

#[test]
fn errors_name_line_and_column() {
    let cases: &[(&str, u32, u32, LevelErrorKind)] = &[
        ("name x\n---\n###\n", 1, 1, LevelErrorKind::MissingColon),
        ("colour: red\n---\n###\n", 1, 1, LevelErrorKind::UnknownKey),
        ("short_mm: 2.0001\n---\n", 1, 11, LevelErrorKind::BadNumber),
        ("long_mm: abc\n---\n", 1, 10, LevelErrorKind::BadNumber),
        ("restitution: 1.5\n---\n", 1, 14, LevelErrorKind::OutOfRange),
        (
            "effects: rolling, flying\n---\n",
            1,
            19,
            LevelErrorKind::UnknownEffect,
        ),
        ("name: a\n#####\n", 3, 1, LevelErrorKind::MissingSeparator),
        ("---\n", 2, 1, LevelErrorKind::EmptyGrid),
        ("---\n#####\n#S.G#\n####\n", 4, 5, LevelErrorKind::RaggedRow),
        (
            "---\n#####\n#S.G#\n######\n",
            4,
            6,
            LevelErrorKind::RaggedRow,
        ),
        ("---\n#####\n#SxG#\n#####\n", 3, 3, LevelErrorKind::BadTile),
        ("---\n#####\n#.SG#\n#####\n", 3, 3, LevelErrorKind::NotACell),
        (
            "---\n#####\n#..G#\n#####\n",
            4,
            1,
            LevelErrorKind::StartCount,
        ),
        (
            "---\n#####\n#S..#\n#####\n",
            4,
            1,
            LevelErrorKind::GoalCount,
        ),
        (
            "marble_radius_mm: 5\n---\n#####\n#S.G#\n",
            1,
            19,
            LevelErrorKind::MarbleTooBig,
        ),
        (
            "\n\nname: ok\n  colour: x\n---\n",
            4,
            3,
            LevelErrorKind::UnknownKey,
        ),
    ];
    for &(src, line, column, kind) in cases {
        let e = error_at(src);
        assert_eq!((e.line, e.column, e.kind), (line, column, kind), "{src:?}");
        let text = e.to_string();
        assert!(text.starts_with(&format!("{line}:{column}: ")), "{text}");
    }
}

#[test]
fn too_large_grids_are_refused() {
    let row = "#".repeat(129);
    let src = format!("---\n{row}\n");
    assert_eq!(error_at(&src).kind, LevelErrorKind::TooLarge);
    let mut tall = String::from("---\n");
    for _ in 0..128 {
        tall.push_str("###\n");
    }
    assert_eq!(error_at(&tall).kind, LevelErrorKind::TooLarge);
}

#[test]
fn crlf_and_trailing_spaces_are_fine() {
    let l = parse::<W>("name: x \r\n---\r\n#####  \r\n#S.G#\r\n#####\r\n").unwrap();
    assert_eq!(l.info.name, "x");
    assert_eq!((l.info.nx, l.info.nz), (5, 3));
}

#[test]
fn the_largest_grid_parses_and_plays() {
    // 127 × 127 tiles, walled, start in one corner and goal in the other.
    let mut src = String::from("---\n");
    for k in 0..127 {
        let row: String = (0..127)
            .map(|i| {
                if i == 0 || k == 0 || i == 126 || k == 126 {
                    '#'
                } else if (i, k) == (1, 1) {
                    'S'
                } else if (i, k) == (125, 125) {
                    'G'
                } else {
                    '.'
                }
            })
            .collect();
        src.push_str(&row);
        src.push('\n');
    }
    assert!(words_needed(&src) <= W);
    let l = parse::<W>(&src).unwrap();
    let mut g = Game::<fixed::types::I8F24>::new(l.view(), GameConfig::DEFAULT).unwrap();
    // Rolled diagonally across the whole board, far from the origin, it arrives.
    g.set_gravity_mg([300, -950, 300]);
    let mut frames = 0;
    while g.frame() == Phase::Playing {
        frames += 1;
        assert!(frames < 2000, "never arrived");
    }
    assert_eq!(g.phase(), Phase::Won);
}
