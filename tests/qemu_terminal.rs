//! QEMU's terminal (`board::qemu::terminal::draw`): a level with
//! storeys is drawn with every storey as a map below the status lines, side
//! by side, top storey first, the marbles on their own storey's map; a
//! one-storey level draws no maps, and the screen is cleared below what was
//! drawn so that a level before's maps do not linger.
//!
//! `cargo test --features app --test qemu_terminal` (the terminal, like the
//! virtual matrix, is built with the firmware tasks, feature `app`).

use marble_rolling::app::Console;
use marble_rolling::board::qemu::terminal::{
    draw, grey, map_window, shade, MapWindow, MAPS_COLUMNS, MAP_ROWS,
};
use marble_rolling::board::qemu::{self, HEIGHT, WIDTH};
use marble_rolling::game::endless::{Endless, MazeSlot, Seeds};
use marble_rolling::game::level::LevelView;
use marble_rolling::game::levels::{by_name, LEVELS};
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::matrix::{Frame, MAX_BRIGHTNESS};
use marble_rolling::player::{MarbleSpot, Player, Status};
use marble_rolling::render::storey_tile;

/// QEMU's player: the board's matrix, the autopilot, the event stepper.
type QemuPlayer = Player<'static, WIDTH, HEIGHT, true, true>;

/// The terminal: every byte written.
#[derive(Default)]
struct Screen(Vec<u8>);

impl Console for Screen {
    fn write(&mut self, bytes: &[u8]) {
        self.0.extend_from_slice(bytes);
    }
}

/// `draw`'s bytes for `status` (a first draw: the screen cleared).
fn drawn(frame: &Frame<WIDTH, HEIGHT>, status: &Status) -> Vec<u8> {
    drawn_maze(frame, status, None)
}

/// [`drawn`] with `maze` on show.
fn drawn_maze(frame: &Frame<WIDTH, HEIGHT>, status: &Status, maze: Option<&LevelView>) -> Vec<u8> {
    let mut screen = Screen::default();
    draw(&mut screen, frame, status, maze, true);
    screen.0
}

/// The text a terminal shows: the escape sequences (`ESC [ … final byte`)
/// and carriage returns removed.
fn plain(bytes: &[u8]) -> String {
    let text = String::from_utf8(bytes.to_vec()).expect("UTF-8");
    let mut out = String::new();
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        match c {
            '\x1b' => {
                assert_eq!(chars.next(), Some('['), "a CSI sequence");
                for c in chars.by_ref() {
                    if ('@'..='~').contains(&c) {
                        break;
                    }
                }
            }
            '\r' => {}
            c => out.push(c),
        }
    }
    out
}

fn two_floors() -> (usize, LevelView<'static>) {
    by_name("two-floors").expect("built-in level two-floors")
}

fn status_of(player: &QemuPlayer) -> Status {
    player.status()
}

/// The maps' lines of `text`: the title line and the `rows` map rows below.
/// Returns the titles' character columns and the rows.
fn maps(text: &str, storeys: usize, rows: usize) -> (Vec<usize>, Vec<Vec<char>>) {
    let lines: Vec<&str> = text.lines().collect();
    let top_title = format!("storey {} (top)", storeys - 1);
    let at = lines
        .iter()
        .position(|line| line.contains(&top_title))
        .unwrap_or_else(|| panic!("no title {top_title:?} in\n{text}"));
    let title: Vec<char> = lines[at].chars().collect();
    let columns = (0..storeys)
        .rev()
        .map(|storey| {
            let name: Vec<char> = if storey == storeys - 1 {
                top_title.chars().collect()
            } else {
                format!("storey {storey}").chars().collect()
            };
            title
                .windows(name.len())
                .position(|w| w == name.as_slice())
                .unwrap_or_else(|| panic!("no title of storey {storey} in {:?}", lines[at]))
        })
        .collect();
    let rows = lines[at + 1..at + 1 + rows]
        .iter()
        .map(|line| line.chars().collect())
        .collect();
    (columns, rows)
}

/// Map `storey`'s row `k` as the terminal should show it (whole maze, two
/// characters a tile), marbles at `marbles` (tile, storey) drawn full.
fn expected_row(
    view: &LevelView<'_>,
    k: i32,
    storey: i32,
    blink: bool,
    marbles: &[((i32, i32), i32)],
) -> String {
    (0..i32::from(view.info.nx))
        .map(|i| {
            let level = if marbles.contains(&((i, k), storey)) {
                MAX_BRIGHTNESS
            } else {
                storey_tile(view, i, k, storey, blink)
            };
            shade(level).repeat(2)
        })
        .collect()
}

#[test]
fn the_status_carries_each_marble_in_play_and_its_storey() {
    let (index, view) = two_floors();
    let mut player = QemuPlayer::new(&LEVELS, index, SYNTHETIC_TILT, true).expect("level");
    let start = view.info.starts()[0];
    assert_eq!(start.storey, 1, "two-floors starts on its top storey");
    let spot = status_of(&player).marbles[0].expect("the marble is in play");
    assert_eq!(
        spot.tile(),
        (i32::from(start.i), i32::from(start.k)),
        "{spot:?}"
    );
    assert_eq!(spot.storey, 1);
    assert!(
        status_of(&player).marbles[1..].iter().all(Option::is_none),
        "one marble on two-floors"
    );
    // The autopilot drops through the hole: the status follows it down.
    let mut frames = 0;
    let down = loop {
        player.tick(AccelMg::LEVEL, false);
        frames += 1;
        if let Some(spot) = status_of(&player).marbles[0] {
            if spot.storey == 0 {
                break spot;
            }
        }
        assert!(frames < 60 * 128, "the marble never reached storey 0");
    };
    // It fell through the hole (the only one): in the hole's tile.
    let hole = (0..i32::from(view.info.nx))
        .flat_map(|i| (0..i32::from(view.info.nz)).map(move |k| (i, k)))
        .find(|&(i, k)| storey_tile(&view, i, k, 1, true) == 0)
        .expect("two-floors has a hole");
    assert_eq!(down.tile(), hole, "{down:?}");
}

#[test]
fn two_floors_shows_both_storeys_side_by_side_the_marble_on_the_top_one() {
    let (index, view) = two_floors();
    let mut player = QemuPlayer::new(&LEVELS, index, SYNTHETIC_TILT, false).expect("level");
    let frame = player.render();
    let status = status_of(&player);
    assert_eq!(status.frames, 0, "the goal is lit at frame 0");
    let text = plain(&drawn(&frame, &status));
    println!("{text}");

    let nz = usize::from(view.info.nz);
    let (columns, rows) = maps(&text, 2, nz);
    assert!(columns[0] < columns[1], "top storey first: {columns:?}");
    let start = view.info.starts()[0];
    let marble = ((i32::from(start.i), i32::from(start.k)), 1);
    let width = 2 * usize::from(view.info.nx);
    let full = shade(MAX_BRIGHTNESS).chars().next().expect("a character");
    for (k, row) in rows.iter().enumerate() {
        let k = k as i32;
        let top: String = row[columns[0]..columns[0] + width].iter().collect();
        let lower: String = row[columns[1]..columns[1] + width].iter().collect();
        assert_eq!(top, expected_row(&view, k, 1, true, &[marble]), "row {k}");
        assert_eq!(lower, expected_row(&view, k, 0, true, &[]), "row {k}");
        assert_eq!(
            top.contains(full),
            k == marble.0 .1,
            "the marble on the top storey's map, row {k}: {top}"
        );
        assert!(!lower.contains(full), "no marble on storey 0: {lower}");
    }
    // The maps are the last lines drawn, and the rest of the screen is cleared.
    assert_eq!(text.lines().count(), {
        let lines: Vec<&str> = text.lines().collect();
        lines
            .iter()
            .position(|l| l.contains("storey 1 (top)"))
            .unwrap()
            + 1
            + nz
    });
    assert!(drawn(&frame, &status).ends_with(b"\x1b[K\r\n\x1b[J"));
}

#[test]
fn a_marble_on_the_lower_storey_is_drawn_on_its_map_only() {
    let (index, view) = two_floors();
    let tile = (5, 3);
    let spot = MarbleSpot {
        i: tile.0 as i16,
        k: tile.1 as i16,
        storey: 0,
    };
    assert_eq!(spot.tile(), tile);
    let status = Status {
        level: index as u8,
        marbles: [Some(spot), None, None, None],
        ..Status::START
    };
    let text = plain(&drawn(&Frame::new(), &status));
    let (columns, rows) = maps(&text, 2, usize::from(view.info.nz));
    let width = 2 * usize::from(view.info.nx);
    for (k, row) in rows.iter().enumerate() {
        let k = k as i32;
        let top: String = row[columns[0]..columns[0] + width].iter().collect();
        let lower: String = row[columns[1]..columns[1] + width].iter().collect();
        assert_eq!(top, expected_row(&view, k, 1, true, &[]), "row {k}");
        assert_eq!(
            lower,
            expected_row(&view, k, 0, true, &[(tile, 0)]),
            "row {k}"
        );
    }
    // The full-brightness character is the marble's alone on the lower map
    // (storey 0 has no goal lit that bright).
    let full = shade(MAX_BRIGHTNESS);
    let lower_marbles: usize = rows
        .iter()
        .map(|row| {
            let lower: String = row[columns[1]..columns[1] + width].iter().collect();
            lower.matches(full).count()
        })
        .sum();
    assert_eq!(lower_marbles, 2, "one tile, two characters");
}

#[test]
fn the_goal_blinks_on_the_maps_as_on_the_matrix() {
    let (index, view) = two_floors();
    let goal = view.info.goals()[0];
    let at = |frames: u32| {
        let status = Status {
            level: index as u8,
            frames,
            ..Status::START
        };
        let text = plain(&drawn(&Frame::new(), &status));
        let (columns, rows) = maps(&text, 2, usize::from(view.info.nz));
        let column = columns[1] + 2 * usize::from(goal.i);
        rows[usize::from(goal.k)][column]
    };
    let lit = at(0);
    // A quarter second later the goal is dark (renderer's blink_on).
    let dark = at(32);
    assert_ne!(lit, dark, "the goal blinks");
    assert_eq!(
        lit.to_string(),
        shade(storey_tile(
            &view,
            i32::from(goal.i),
            i32::from(goal.k),
            0,
            true
        ))
    );
}

#[test]
fn a_one_storey_level_draws_no_maps_and_clears_below() {
    let index = LEVELS
        .iter()
        .position(|level| level.info.storeys == 1)
        .expect("a one-storey level");
    let mut player = QemuPlayer::new(&LEVELS, index, SYNTHETIC_TILT, false).expect("level");
    let frame = player.render();
    let status = status_of(&player);
    assert_eq!(
        status.marbles, [None; 4],
        "a one-storey level's status carries no marbles (nothing shows them)"
    );
    let bytes = drawn(&frame, &status);
    let text = plain(&bytes);
    assert!(!text.contains("storey"), "{text}");
    // The keys' lines are the last; then the rest of the screen is cleared
    // (a level with storeys before left its maps there).
    assert!(
        bytes.ends_with(b"p autopilot, m sound, q quit\x1b[K\r\n\x1b[J"),
        "{text}"
    );
    // Marbles in the status would not change a one-storey screen.
    let elsewhere = Status {
        marbles: [Some(MarbleSpot {
            i: 1,
            k: 1,
            storey: 0,
        }); 4],
        ..status
    };
    assert_eq!(drawn(&frame, &elsewhere), bytes);
}

#[test]
fn the_matrix_and_status_lines_come_first_unchanged() {
    // A level with storeys draws the one-storey screen, then its maps.
    let (index, _) = two_floors();
    let status = Status {
        level: index as u8,
        ..Status::START
    };
    let frame = Frame::filled(3);
    let bytes = drawn(&frame, &status);
    let keys = b"p autopilot, m sound, q quit\x1b[K\r\n";
    let end = bytes
        .windows(keys.len())
        .position(|w| w == keys)
        .expect("the keys' line")
        + keys.len();
    let head = String::from_utf8(bytes[..end].to_vec()).unwrap();
    let row = format!("    {}\x1b[0m\x1b[K\r\n", {
        let s = shade(3);
        format!("\x1b[38;5;{}m{s}{s}", grey(3)).repeat(WIDTH)
    });
    assert_eq!(head.matches(&row).count(), HEIGHT, "{head:?}");
    assert!(head.starts_with("\x1b[2J\x1b[?25l\x1b[H  Marble Rolling (QEMU virtual matrix)"));
    assert!(!plain(&bytes[..end]).contains("storey"));
    assert!(plain(&bytes[end..]).contains("storey 1 (top)"));
}

#[test]
fn wide_mazes_show_a_window_around_the_marble_within_100_columns() {
    // Every built-in level with storeys fits whole.
    for level in LEVELS.iter().filter(|level| level.info.storeys > 1) {
        let window = map_window(level.info.nx, level.info.nz, level.info.storeys, None);
        assert_eq!(
            window,
            MapWindow {
                i0: 0,
                k0: 0,
                w: i32::from(level.info.nx),
                h: i32::from(level.info.nz)
            },
            "{}",
            level.info.name
        );
    }
    // The largest grid, 127 × 127 on 2, 3 and 4 storeys.
    for storeys in 2..=4u8 {
        let window = map_window(127, 127, storeys, Some((60, 70)));
        let n = usize::from(storeys);
        // Indent, maps (two columns a tile, at least a title wide), gaps.
        let columns = 4 + n * (2 * window.w as usize).max(14) + 2 * (n - 1);
        assert!(columns <= MAPS_COLUMNS, "{storeys} storeys: {columns}");
        assert!(window.w >= 11, "{window:?}");
        assert_eq!(window.h, MAP_ROWS as i32);
        assert_eq!(window.i0, 60 - window.w / 2, "centred on the marble");
        assert_eq!(window.k0, 70 - window.h / 2);
    }
    // Clamped to the maze at its edges.
    let corner = map_window(127, 127, 4, Some((0, 126)));
    assert_eq!((corner.i0, corner.k0), (0, 127 - corner.h));
    let far = map_window(127, 20, 3, Some((126, 0)));
    assert_eq!((far.i0, far.k0), (127 - far.w, 0));
    // A maze narrower than a map: whole, whatever the marble.
    let small = map_window(11, 5, 4, Some((9, 4)));
    assert_eq!((small.i0, small.k0, small.w, small.h), (0, 0, 11, 5));
}

#[test]
fn a_generated_maze_is_named_and_its_storeys_drawn() {
    let frame = Frame::filled(1);
    let builtin = plain(&drawn(
        &frame,
        &Status {
            level: 1,
            ..Status::START
        },
    ));
    assert!(
        builtin.contains(&format!(
            "level 2/{} {}:",
            LEVELS.len(),
            LEVELS[1].info.name
        )),
        "{builtin}"
    );
    // Level 12 of the endless run, the second maze: two storeys.
    let endless = Endless {
        from_region: 0,
        builtins: LEVELS.len(),
        reach: qemu::MAZE_REACH,
        seeds: Seeds::Count,
    };
    let number = LEVELS.len() + 1;
    let args = endless.maze(number).expect("a maze");
    assert_eq!(args.storeys, 2);
    let mut slot = MazeSlot::<{ qemu::MAZE_REACH.words() }, { qemu::MAZE_REACH.text_bytes() }>::new(
        qemu::MAZE_REACH,
    );
    let maze = slot.make(args).expect("made");
    let status = Status {
        level: number as u8,
        maze: Some(args),
        ..Status::START
    };
    let screen = plain(&drawn_maze(&frame, &status, Some(&maze)));
    assert!(
        screen.contains("level 12 maze-12-4x4x2-d1: playing"),
        "{screen}"
    );
    assert!(screen.contains("storey 1 (top)"), "{screen}");
    assert!(screen.contains("storey 0"), "{screen}");
    // Without the maze (it could not be made), the line still says what it is.
    let bare = plain(&drawn(&frame, &status));
    assert!(
        bare.contains("level 12 (a generated maze): playing"),
        "{bare}"
    );
    assert!(!bare.contains("storey 1 (top)"), "{bare}");
}
