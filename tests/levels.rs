//! The level format: built-ins, defaults, the effects list, and errors with line
//! and column.
mod common;

use marble_rolling::game::level::{
    parse, text, words_needed, Cell, LevelError, LevelErrorKind, NumberKey, MAX_PITCH_UM,
    MIN_PITCH_UM,
};
use marble_rolling::game::levels::{by_name, LEVELS};
use marble_rolling::game::rules::{Game, GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::tilt::GravityMg;
use marble_rolling::physics::geometry::tiles::LayoutError;
use marble_rolling::physics::{MicroF32, Params, PhysicsSpec, Scalar, SetupError};

use common::{cell_centre, spec_in, Stepping};
use marble_rolling::physics::{Effects, World};

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
    assert_eq!(l.info.starts(), &[Cell::new(1, 1, 0)]);
    assert_eq!(l.info.goals(), &[Cell::new(3, 1, 0)]);
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
    // The list is exact: rolling is not in it, so it is off.
    assert!(!s.effects.rolling);
    assert_eq!(l.info.time_limit_s, 90);
}

#[test]
fn errors_name_line_and_column() {
    let cases: &[(&str, u32, u32, LevelErrorKind)] = &[
        ("name x\n---\n###\n", 1, 1, LevelErrorKind::MissingColon),
        ("colour: red\n---\n###\n", 1, 1, LevelErrorKind::UnknownKey),
        ("short_mm: 2.0001\n---\n", 1, 11, LevelErrorKind::BadNumber),
        ("long_mm: abc\n---\n", 1, 10, LevelErrorKind::BadNumber),
        (
            "restitution: 1.5\n---\n",
            1,
            14,
            LevelErrorKind::OutOfRange {
                key: NumberKey::Restitution,
            },
        ),
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
            LevelErrorKind::MarbleTooBig {
                radius_um: 5000,
                long_um: 10000,
            },
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
    g.set_gravity_mg(GravityMg::new(300, -950, 300));
    let mut frames = 0;
    while g.frame() == Phase::Playing {
        frames += 1;
        assert!(frames < 2000, "never arrived");
    }
    assert_eq!(g.phase(), Phase::Won);
}

/// A level with the given header over a small playable grid.
fn with_header(header: &str) -> String {
    format!("{header}---\n#####\n#S.G#\n#####\n")
}

#[test]
fn what_setup_refuses_is_a_parse_error_at_the_value() {
    // (header, line, column, kind, words the message must contain)
    let cases: &[(&str, u32, u32, LevelErrorKind, &[&str])] = &[
        // A 0.004 mm pitch is refused at parsing, where the line is known, not at setup.
        (
            "short_mm: 0.001\nlong_mm: 0.003\nmarble_radius_mm: 0.001\n",
            2,
            10,
            LevelErrorKind::PitchOutOfRange {
                short_um: 1,
                long_um: 3,
            },
            &[
                "cell pitch",
                "short_mm + long_mm",
                "1 ..= 100 mm",
                "0.001 + 0.003 = 0.004 mm",
            ],
        ),
        // Item 4.2: the marble fits (2 × 25 = 50 < 50.001); the pitch is too long.
        (
            "short_mm: 50\nlong_mm: 50.001\nmarble_radius_mm: 25\n",
            2,
            10,
            LevelErrorKind::PitchOutOfRange {
                short_um: 50_000,
                long_um: 50_001,
            },
            &["cell pitch", "1 ..= 100 mm", "50 + 50.001 = 100.001 mm"],
        ),
        // Only short_mm given: the default long_mm (10) completes the pitch.
        (
            "name: x\nshort_mm: 90.001\n",
            2,
            11,
            LevelErrorKind::PitchOutOfRange {
                short_um: 90_001,
                long_um: 10_000,
            },
            &["90.001 + 10 = 100.001 mm"],
        ),
        // The later of the two values is the one reported.
        (
            "long_mm: 0.5\nshort_mm: 0.499\n",
            2,
            11,
            LevelErrorKind::PitchOutOfRange {
                short_um: 499,
                long_um: 500,
            },
            &["0.499 + 0.5 = 0.999 mm"],
        ),
        (
            "long_mm: 8\nmarble_radius_mm: 4\n",
            2,
            19,
            LevelErrorKind::MarbleTooBig {
                radius_um: 4000,
                long_um: 8000,
            },
            &[
                "marble does not fit a cell",
                "less than long_mm",
                "2 × 4 = 8 mm",
                "long_mm 8 mm",
            ],
        ),
        (
            "marble_radius_mm: 3\nlong_mm: 5.999\n",
            2,
            10,
            LevelErrorKind::MarbleTooBig {
                radius_um: 3000,
                long_um: 5999,
            },
            &["2 × 3 = 6 mm against long_mm 5.999 mm"],
        ),
        // Only long_mm given: the default radius (3.5 mm) no longer fits.
        (
            "long_mm: 7\n",
            1,
            10,
            LevelErrorKind::MarbleTooBig {
                radius_um: 3500,
                long_um: 7000,
            },
            &["2 × 3.5 = 7 mm"],
        ),
    ];
    for &(header, line, column, kind, words) in cases {
        let src = with_header(header);
        let e = error_at(&src);
        assert_eq!((e.line, e.column, e.kind), (line, column, kind), "{src:?}");
        let text = e.to_string();
        assert!(text.starts_with(&format!("{line}:{column}: ")), "{text}");
        for w in words {
            assert!(text.contains(w), "{text:?} lacks {w:?}");
        }
        assert!(!text.contains("Layout") && !text.contains('{'), "{text}");
    }
}

/// Sets a parsed level up the way the tools do, with every backend.
fn sets_up(src: &str) -> Result<(), String> {
    let l = parse::<W>(src).map_err(|e| e.to_string())?;
    fn on<S: Scalar>(l: &marble_rolling::game::level::Level<'_, W>) -> Result<(), String> {
        Session::<S>::new(l.view(), GameConfig::DEFAULT, SYNTHETIC_TILT)
            .map(|_| ())
            .map_err(|e| format!("{}: {e}", S::NAME))
    }
    on::<fixed::types::I8F24>(&l)?;
    on::<fixed::types::I32F32>(&l)?;
    on::<fixed::types::I16F16>(&l)?;
    on::<f32>(&l)?;
    on::<MicroF32>(&l)?;
    on::<f64>(&l)
}

#[test]
fn just_inside_the_limits_sets_up_and_just_outside_is_refused() {
    let inside = [
        // The smallest pitch, 1 mm, with the largest marble it takes.
        "short_mm: 0.2\nlong_mm: 0.8\nmarble_radius_mm: 0.399\n",
        "short_mm: 0.001\nlong_mm: 0.999\nmarble_radius_mm: 0.001\n",
        // The largest pitch, 100 mm.
        "short_mm: 2\nlong_mm: 98\nmarble_radius_mm: 48.999\n",
        "short_mm: 50\nlong_mm: 50\nmarble_radius_mm: 24.999\n",
        "short_mm: 99.997\nlong_mm: 0.003\nmarble_radius_mm: 0.001\n",
    ];
    for h in inside {
        sets_up(&with_header(h)).unwrap_or_else(|e| panic!("{h:?}: {e}"));
    }
    let outside = [
        (
            "short_mm: 0.2\nlong_mm: 0.799\nmarble_radius_mm: 0.399\n",
            2,
        ),
        (
            "short_mm: 2\nlong_mm: 98.001\nmarble_radius_mm: 48.999\n",
            2,
        ),
        ("short_mm: 2\nlong_mm: 98\nmarble_radius_mm: 49\n", 3),
        ("short_mm: 0.2\nlong_mm: 0.8\nmarble_radius_mm: 0.4\n", 3),
        ("short_mm: 0\n", 1),
        ("marble_radius_mm: 0\n", 1),
        ("long_mm: 100.001\n", 1),
    ];
    for (h, line) in outside {
        let e = error_at(&with_header(h));
        assert_eq!(e.line, line, "{h:?}: {e}");
    }
}

/// The parser's rules and `Params::new`'s agree (they are written twice: the parser is
/// a `const fn` and the setup is generic over the scalar): around every limit, a
/// spec parses exactly when it sets up.
#[test]
fn parser_and_setup_agree_around_the_limits() {
    let around = |x: u32| [x.saturating_sub(1), x, x + 1];
    let mut widths = vec![
        1, 2, 3, 500, 998, 999, 1000, 2000, 10_000, 49_999, 50_000, 50_001,
    ];
    widths.extend(around(MIN_PITCH_UM / 2));
    widths.extend(around(MAX_PITCH_UM / 2));
    widths.extend(around(MAX_PITCH_UM - 1000));
    widths.extend(around(MAX_PITCH_UM - 1));
    widths.extend(around(MAX_PITCH_UM));
    let mut checked = [0usize; 2];
    for &short_um in &widths {
        for &long_um in &widths {
            for radius_um in [
                0,
                1,
                (long_um / 2).saturating_sub(1),
                long_um / 2,
                long_um.div_ceil(2),
            ] {
                let spec = PhysicsSpec {
                    short_um,
                    long_um,
                    radius_um,
                    ..PhysicsSpec::DEFAULT
                };
                let mm = |um: u32| format!("{}.{:03}", um / 1000, um % 1000);
                let src = with_header(&format!(
                    "short_mm: {}\nlong_mm: {}\nmarble_radius_mm: {}\n",
                    mm(short_um),
                    mm(long_um),
                    mm(radius_um)
                ));
                let parsed = parse::<W>(&src).is_ok();
                let params = Params::<fixed::types::I8F24>::new(spec);
                assert_eq!(parsed, params.is_ok(), "{src:?}: {params:?}");
                if parsed {
                    sets_up(&src).unwrap_or_else(|e| panic!("{src:?}: {e}"));
                }
                checked[parsed as usize] += 1;
            }
        }
    }
    assert!(checked[0] > 100 && checked[1] > 100, "{checked:?}");
}

#[test]
fn setup_errors_read_as_words() {
    let cases = [
        (
            SetupError::Layout(LayoutError::PitchOutOfRange),
            "short_mm + long_mm is outside 1 ..= 100 mm",
        ),
        (
            SetupError::Layout(LayoutError::ZeroWidth),
            "must not be zero",
        ),
        (SetupError::MarbleSize, "marble does not fit a cell"),
        (SetupError::Parameter, "restitution"),
        (SetupError::MarbleCount, "marble start"),
        (SetupError::BadStart(1), "marble start 2"),
    ];
    for (e, words) in cases {
        let text = e.to_string();
        assert!(text.contains(words), "{text:?} lacks {words:?}");
        assert_ne!(text, format!("{e:?}"));
    }
}

#[test]
fn a_byte_order_mark_is_skipped() {
    let plain = "name: bom\nshort_mm: 1.5\neffects: friction\n---\n#####\n#S.G#\n#####\n";
    let bom = format!("\u{feff}{plain}");
    assert_eq!(bom.as_bytes()[..3], [0xEF, 0xBB, 0xBF]);
    assert_eq!(words_needed(&bom), words_needed(plain));
    let (a, b) = (parse::<W>(plain).unwrap(), parse::<W>(&bom).unwrap());
    assert_eq!(a, b);
    assert_eq!(b.info.name, "bom");
    // The grid may start right after the mark.
    let grid = "---\n#####\n#S.G#\n#####\n";
    assert_eq!(
        parse::<W>(&format!("\u{feff}{grid}")).unwrap(),
        parse::<W>(grid).unwrap()
    );
    // Columns on line 1 count from the first visible character.
    for (src, column) in [("colour: x\n---\n", 1), ("restitution: 2\n---\n", 14)] {
        let e = error_at(&format!("\u{feff}{src}"));
        assert_eq!((e.line, e.column), (1, column), "{src:?}: {e}");
        assert_eq!(e, error_at(src));
    }
    // Only at the very start: a second mark is an unknown key.
    let e = error_at(&format!("\u{feff}\u{feff}{plain}"));
    assert_eq!(
        (e.line, e.column, e.kind),
        (1, 1, LevelErrorKind::UnknownKey)
    );
}

/// A built-in level may carry the mark too: the `const fn` parser skips it at
/// compile time.
#[test]
fn a_byte_order_mark_is_skipped_at_compile_time() {
    static BOM: marble_rolling::game::level::LevelView<'static> =
        marble_rolling::builtin_level!("\u{feff}name: bom\n---\n#####\n#S.G#\n#####\n");
    assert_eq!(BOM.info.name, "bom");
    assert_eq!(BOM.info.goals(), &[Cell::new(3, 1, 0)]);
}

/// A corridor 127 tiles long under `header`: the marble starts at its west end.
fn corridor(header: &str) -> String {
    let wall = "#".repeat(127);
    format!("{header}---\n{wall}\n#S{}G#\n{wall}\n", ".".repeat(123))
}

fn effects_of(header: &str) -> Effects {
    parse::<W>(&corridor(header))
        .unwrap_or_else(|e| panic!("{header:?}: {e}"))
        .info
        .spec
        .effects
}

#[test]
fn effects_is_the_exact_list() {
    let only = |rolling, friction, board_motion| Effects {
        rolling,
        friction,
        board_motion,
        ..Effects::NONE
    };
    let cases: &[(&str, Effects)] = &[
        // Without the key: rolling, as always.
        ("", only(true, false, false)),
        ("name: x\n", only(true, false, false)),
        // Empty or `none`: nothing.
        ("effects:\n", Effects::NONE),
        ("effects:   \n", Effects::NONE),
        ("effects: none\n", Effects::NONE),
        ("effects: none \r\n", Effects::NONE),
        // Exactly what is listed.
        ("effects: rolling\n", only(true, false, false)),
        ("effects: friction\n", only(false, true, false)),
        ("effects: board_motion\n", only(false, false, true)),
        ("effects: friction,board_motion\n", only(false, true, true)),
        (
            "effects: rolling, friction, board_motion\n",
            only(true, true, true),
        ),
        ("effects: rolling, , friction,\n", only(true, true, false)),
        // A later line replaces an earlier one.
        (
            "effects: friction\neffects: rolling\n",
            only(true, false, false),
        ),
        ("effects: rolling\neffects:\n", Effects::NONE),
    ];
    for &(header, want) in cases {
        assert_eq!(effects_of(header), want, "{header:?}");
    }
    // Holes and several marbles come from the grid, whatever the list says.
    let l = parse::<W>("effects: none\n---\n#####\n#S.G#\n#O###\n#S..#\n#####\n").unwrap();
    let e = l.info.spec.effects;
    assert!(e.holes && e.marbles && !e.rolling && !e.friction && !e.board_motion);
    // `none` beside an effect is refused at `none`.
    for (header, column) in [
        ("effects: none, rolling\n", 10),
        ("effects: rolling, none\n", 19),
        ("effects: none, none\n", 16),
    ] {
        let e = error_at(&corridor(header));
        assert_eq!(
            (e.line, e.column, e.kind),
            (1, column, LevelErrorKind::UnknownEffect),
            "{header:?}"
        );
        assert!(e.to_string().contains("none, alone"), "{e}");
    }
}

/// A level's effects list is what the step runs: every effect it leaves out
/// never runs (its `StepStats` counter stays at zero), every one it names does.
#[test]
fn each_effect_left_out_never_runs() {
    type S = fixed::types::I8F24;
    let lists = [
        "",
        "none",
        "rolling",
        "friction",
        "board_motion",
        "rolling, friction",
        "rolling, board_motion",
        "friction, board_motion",
        "rolling, friction, board_motion",
    ];
    for list in lists {
        let src = corridor(&format!("effects: {list}\n"));
        let l = parse::<W>(&src).unwrap();
        let fx = l.info.spec.effects;
        for st in [Stepping::Fixed, Stepping::Events] {
            let spec = PhysicsSpec {
                effects: fx,
                ..spec_in(st, fx)
            };
            let p = Params::<S>::new(spec).unwrap();
            let mut w: World<'_, S, 4> =
                World::new(p, l.grid.view(), &[cell_centre(&p, 1, 1)]).unwrap();
            // Towards the far end and against the corridor's side wall.
            w.set_gravity_mg([300, -950, 200]);
            for _ in 0..steps_per_second(&p) {
                w.step();
            }
            let s = w.stats;
            assert_eq!(s.friction_runs > 0, fx.friction, "{list:?} {st:?}: {s:?}");
            assert_eq!(
                s.board_motion_runs > 0,
                fx.board_motion,
                "{list:?} {st:?}: {s:?}"
            );
            // No hole and one marble: neither the 3-D nor the pair code runs.
            assert_eq!((s.space_runs, s.pair_runs), (0, 0), "{list:?} {st:?}");
            assert!(s.contacts > 0, "{list:?} {st:?}: walls are always on");
        }
    }
}

fn steps_per_second<S: Scalar>(p: &Params<S>) -> u32 {
    1 << p.k
}

/// Down a 0.05 g incline for 1 s, a level's marble slides `½·g·sinθ·t²` with
/// `effects: none` (and with `effects:` empty) and rolls 5/7 of it with
/// `rolling` (and without the key): the list decides the physics.
fn incline_as_listed<S: Scalar>(st: Stepping) {
    for (header, rolling) in [
        ("effects: none\n", false),
        ("effects:\n", false),
        ("effects: rolling\n", true),
        ("", true),
    ] {
        let src = corridor(header);
        let l = parse::<W>(&src).unwrap();
        let fx = l.info.spec.effects;
        assert_eq!(fx.rolling, rolling, "{header:?}");
        let p = Params::<S>::new(PhysicsSpec {
            effects: fx,
            ..spec_in(st, fx)
        })
        .unwrap();
        let start = cell_centre(&p, 1, 1);
        let mut w: World<'_, S, 4> = World::new(p, l.grid.view(), &[start]).unwrap();
        w.set_gravity_mg([50, -999, 0]);
        for _ in 0..steps_per_second(&p) {
            w.step();
        }
        let x = p.layout.to_mm(w.marbles()[0].pos.x) - p.layout.to_mm(start.0);
        let a = 0.05 * 9806.65 * if rolling { 5.0 / 7.0 } else { 1.0 };
        let want = 0.5 * a;
        let err = (x - want).abs();
        // As tests/analytic.rs's incline: I16F16 resolves ½·a·dt² to 1.5·10⁻⁵ pitch.
        let bound = if S::NAME == "i16f16" { 0.15 } else { 0.01 };
        assert!(
            err < bound,
            "{} {st:?} {header:?}: {x} mm, want {want} mm",
            S::NAME
        );
        // The other list is far off: 2/7 of the distance (35 mm) apart.
        let other = 0.5 * 0.05 * 9806.65 * if rolling { 1.0 } else { 5.0 / 7.0 };
        assert!((x - other).abs() > 30.0);
    }
}
for_each_backend_and_mode!(a_levels_effects_list_is_its_physics, incline_as_listed);

#[test]
fn out_of_range_names_the_range() {
    let cases = [
        ("restitution: 1.001", 14, "restitution is 0 ..= 1"),
        ("short_mm: 0", 11, "short_mm is 0.001 ..= 100"),
        ("long_mm: 100.001", 10, "long_mm is 0.001 ..= 100"),
        (
            "marble_radius_mm: 0",
            19,
            "marble_radius_mm is 0.001 ..= 100",
        ),
        (
            "rolling_resistance: 1.000001",
            21,
            "rolling_resistance is 0 ..= 1",
        ),
        ("time_limit_s: 0", 15, "time_limit_s is 1 ..= 3600"),
        ("time_limit_s: 3601", 15, "time_limit_s is 1 ..= 3600"),
        // Too many digits to hold is out of range too, not "not a number".
        (
            "restitution: 100000000000000000000000000000",
            14,
            "restitution is 0 ..= 1",
        ),
    ];
    for (header, column, range) in cases {
        let e = error_at(&with_header(&format!("{header}\n")));
        assert!(
            matches!(e.kind, LevelErrorKind::OutOfRange { .. }),
            "{header}: {e}"
        );
        assert_eq!((e.line, e.column), (1, column), "{header}");
        assert_eq!(
            e.to_string(),
            format!("1:{column}: value out of range: {range}")
        );
    }
    // A huge token is still one short line.
    let huge = format!("time_limit_s: {}\n", "9".repeat(100_000));
    let e = error_at(&with_header(&huge));
    assert_eq!(
        e.to_string(),
        "1:15: value out of range: time_limit_s is 1 ..= 3600"
    );
}

/// A minus sign makes a number below every key's range: the message gives
/// the range at the sign (`time_limit_s: -1` once said "not a number"). A sign
/// with no number after it is still not a number; `-0` is 0.
#[test]
fn a_negative_value_is_out_of_range_with_the_range() {
    for key in NumberKey::ALL {
        let name = key.name();
        let header = format!("{name}: -1\n");
        let e = error_at(&with_header(&header));
        let column = name.len() as u32 + 3;
        assert_eq!(
            (e.line, e.column, e.kind),
            (1, column, LevelErrorKind::OutOfRange { key }),
            "{header}"
        );
        assert_eq!(
            e.to_string(),
            format!("1:{column}: value out of range: {}", key.range_text())
        );
    }
    assert_eq!(
        error_at(&with_header("time_limit_s: -1\n")).to_string(),
        "1:15: value out of range: time_limit_s is 1 ..= 3600"
    );
    for value in ["-", "--1", "-abc", "- 1", "1-"] {
        let e = error_at(&with_header(&format!("time_limit_s: {value}\n")));
        assert_eq!(
            (e.line, e.column, e.kind),
            (1, 15, LevelErrorKind::BadNumber),
            "{value}"
        );
    }
    let source = with_header("restitution: -0\n");
    let zero = parse::<W>(&source).expect("-0 is 0");
    assert_eq!(zero.info.spec.restitution_milli, 0);
}

#[test]
fn bytes_that_are_not_utf8_are_an_error_at_their_line_and_column() {
    let ok = "name: x\n---\n#####\n#S.G#\n#####\n";
    assert_eq!(text(ok.as_bytes()), Ok(ok));
    let cases: &[(&[u8], u32, u32, u8)] = &[
        (b"\xff---\n", 1, 1, 0xFF),
        (b"name: a\xe9b\n---\n", 1, 8, 0xE9),
        (b"name: x\n---\n#####\n#S\x80G#\n", 4, 3, 0x80),
        // Columns count characters, as the parser does; a BOM is not one.
        ("name: é\n".as_bytes(), 0, 0, 0),
        (b"\xef\xbb\xbfname: \xc3\xa9\xfe\n", 1, 8, 0xFE),
        // A character cut short by the end of the file: its first byte.
        (b"name: x\n\xe2\x82", 2, 1, 0xE2),
        // An overlong encoding and a UTF-16 surrogate are not UTF-8.
        (b"name: \xc0\xaf\n", 1, 7, 0xC0),
        (b"---\n\n\xed\xa0\x80", 3, 1, 0xED),
    ];
    for &(bytes, line, column, byte) in cases {
        if line == 0 {
            assert!(text(bytes).is_ok());
            continue;
        }
        let e = text(bytes).expect_err("not UTF-8");
        assert_eq!(
            (e.line, e.column, e.kind),
            (line, column, LevelErrorKind::NotUtf8 { byte }),
            "{bytes:?}"
        );
        assert_eq!(
            e.to_string(),
            format!("{line}:{column}: not UTF-8 (byte 0x{byte:02X})")
        );
    }
}

/// Each key's range in words (its messages, the build error of a built-in
/// level) says what the parser takes: both ends are taken, one step past
/// either is out of range.
#[test]
fn each_keys_range_text_is_its_range() {
    let words = |scaled: u64, decimals: u32| {
        let unit = 10u64.pow(decimals);
        let (whole, frac) = (scaled / unit, scaled % unit);
        if frac == 0 {
            whole.to_string()
        } else {
            let frac = format!("{frac:0width$}", width = decimals as usize);
            format!("{whole}.{}", frac.trim_end_matches('0'))
        }
    };
    for key in NumberKey::ALL {
        let (lo, hi) = key.range();
        let d = key.decimals();
        let (lo_text, hi_text) = (words(lo, d), words(hi, d));
        assert_eq!(
            key.range_text(),
            format!("{} is {lo_text} ..= {hi_text}", key.name())
        );
        let at = |value: String| {
            parse::<W>(&with_header(&format!("{}: {value}\n", key.name()))).map(|_| ())
        };
        for inside in [lo_text, hi_text] {
            if let Err(e) = at(inside.clone()) {
                // The pitch and marble rules may still refuse an end: not its range.
                assert!(
                    !matches!(e.kind, LevelErrorKind::OutOfRange { .. }),
                    "{} {inside}: {e}",
                    key.name()
                );
            }
        }
        let mut outside = vec![words(hi + 1, d)];
        if lo > 0 {
            outside.push(words(lo - 1, d));
        }
        for value in outside {
            let e = at(value.clone()).expect_err("out of range");
            assert_eq!(e.kind, LevelErrorKind::OutOfRange { key }, "{value}");
        }
    }
}
