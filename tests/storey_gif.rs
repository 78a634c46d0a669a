//! The host GIF of a level with storeys: the matrix picture, then every
//! storey's whole map, top storey first (`marble_rolling::host::storey_maps`),
//! composed without a file and recorded by `cargo sim --gif`
//! (`cargo test --features tools --test storey_gif`).

use std::path::PathBuf;

use clap::Parser;
use fixed::types::I8F24;
use marble_rolling::game::level::LevelView;
use marble_rolling::game::levels::by_name;
use marble_rolling::game::rules::{cell_centre, Game, GameConfig};
use marble_rolling::host::gif_out::NO_LED;
use marble_rolling::host::level_picture;
use marble_rolling::host::sim::{simulate, Args};
use marble_rolling::host::storey_maps::{compose, game_image, image_size, GAP_LEDS};
use marble_rolling::matrix::MAX_BRIGHTNESS;
use marble_rolling::physics::{Scalar, Vec3};
use marble_rolling::render::{blink_on, storey_tile, FLOOR, GOAL_ON, HOLE, MARBLE, WALL};

type S = I8F24;

fn builtin(name: &str) -> LevelView<'static> {
    by_name(name)
        .unwrap_or_else(|| panic!("no built-in level {name}"))
        .1
}

fn game(level: LevelView<'static>) -> Game<'static, S> {
    Game::<S>::new(level, GameConfig::DEFAULT).expect("game")
}

/// Puts marble 0 at rest on cell `(i, k)` of `storey` (0: the lowest).
fn place(g: &mut Game<'_, S>, i: u8, k: u8, storey: i32) {
    let p = *g.world().params();
    let (x, z) = cell_centre(&p, i, k);
    let y = p.layout.span_y(2 * storey).1 + p.radius;
    let m = &mut g.world_mut().marbles_mut()[0];
    m.pos = Vec3::new(x, y, z);
    m.vel = Vec3::new(S::ZERO, S::ZERO, S::ZERO);
    assert_eq!(p.layout.storey_of(y), storey, "placed on storey {storey}");
}

/// An `nx`×`nz` region of `img` whose left column is `x0`.
fn region(img: &(usize, usize, Vec<u8>), x0: usize, nx: usize) -> Vec<u8> {
    let (w, h, px) = img;
    (0..*h)
        .flat_map(|y| px[y * w + x0..y * w + x0 + nx].to_vec())
        .collect()
}

/// The bare tiles of `storey` (no marble).
fn bare(level: &LevelView<'_>, storey: i32, blink: bool) -> Vec<u8> {
    let (nx, nz) = (level.info.nx as i32, level.info.nz as i32);
    (0..nz)
        .flat_map(|k| (0..nx).map(move |i| storey_tile(level, i, k, storey, blink)))
        .collect()
}

#[test]
fn two_floors_shows_both_storeys_top_first_with_the_marble_on_its_own() {
    let level = builtin("two-floors");
    assert_eq!(level.info.storeys, 2);
    let (nx, nz) = (level.info.nx as usize, level.info.nz as usize);
    assert_eq!((nx, nz), (11, 5));
    let mut g = game(level);
    let blink = blink_on(g.frames(), g.config().frame_log2);
    assert!(blink, "the goal is lit in frame 0");
    // Picture, gap, upper storey, gap, lower storey.
    let (upper, lower) = (nx + GAP_LEDS, 2 * (nx + GAP_LEDS));
    let expected_w = nx + 2 * (GAP_LEDS + nx);
    assert_eq!(image_size(&level), (expected_w, nz));

    // The marble starts on the upper storey's `S` at (1, 1), a cell's centre:
    // the whole marble on one pixel, saturated.
    let img = game_image(&g);
    assert_eq!(
        (img.0, img.1, img.2.len()),
        (expected_w, nz, expected_w * nz)
    );
    let at = |img: &(usize, usize, Vec<u8>), x: usize, y: usize| img.2[y * img.0 + x];
    assert_eq!(at(&img, upper + 1, 1), MARBLE.min(MAX_BRIGHTNESS));
    assert_eq!(at(&img, lower + 1, 1), WALL, "below the start: a wall");
    assert_eq!(at(&img, lower + 1, 3), GOAL_ON, "the goal below, lit");
    assert_eq!(
        region(&img, lower, nx),
        bare(&level, 0, blink),
        "no marble on the lower storey"
    );
    assert!(region(&img, lower, nx).iter().all(|&b| b < MAX_BRIGHTNESS));
    // The upper map is what the matrix draws of the marble's storey.
    assert_eq!(region(&img, upper, nx), region(&img, 0, nx));
    // The gaps are no LEDs.
    for y in 0..nz {
        for x in (nx..upper).chain(upper + nx..lower) {
            assert_eq!(at(&img, x, y), NO_LED, "gap at ({x}, {y})");
        }
    }
    // Walls where the other storey has none, at the right place on each map:
    // (5, 3) is a wall above and floor below; (5, 1) floor above, wall below;
    // (9, 3) the hole above, floor below. The goal is (1, 3) below.
    assert_eq!(at(&img, upper + 5, 3), WALL);
    assert_eq!(at(&img, lower + 5, 3), FLOOR);
    assert_eq!(at(&img, upper + 5, 1), FLOOR);
    assert_eq!(at(&img, lower + 5, 1), WALL);
    assert_eq!(at(&img, upper + 9, 3), HOLE);
    assert_eq!(at(&img, lower + 9, 3), FLOOR);

    // Dropped to the lower storey at (5, 3): drawn there and not above.
    place(&mut g, 5, 3, 0);
    let img = game_image(&g);
    assert_eq!(at(&img, lower + 5, 3), MARBLE.min(MAX_BRIGHTNESS));
    assert_eq!(at(&img, upper + 5, 3), WALL, "the wall above is bare");
    assert_eq!(region(&img, upper, nx), bare(&level, 1, blink));
    assert_eq!(region(&img, lower, nx), region(&img, 0, nx));
}

#[test]
fn a_marble_between_tiles_is_split_as_on_the_matrix() {
    let level = builtin("two-floors");
    let nx = level.info.nx as usize;
    let mut g = game(level);
    // Halfway between the centres of (3, 1) and (4, 1), a quarter tile down:
    // its light spread over up to four pixels of the upper map.
    let p = *g.world().params();
    let (x0, z0) = cell_centre(&p, 3, 1);
    let (x1, z1) = cell_centre(&p, 4, 2);
    let m = &mut g.world_mut().marbles_mut()[0];
    m.pos = Vec3::new(x0 + (x1 - x0).half(), m.pos.y, z0 + (z1 - z0).half().half());
    let img = game_image(&g);
    let upper = region(&img, nx + GAP_LEDS, nx);
    let bare_upper = bare(&level, 1, blink_on(g.frames(), g.config().frame_log2));
    let lit = upper
        .iter()
        .zip(&bare_upper)
        .filter(|(a, b)| a != b)
        .count();
    assert!(lit >= 2, "spread over {lit} pixels");
    assert_eq!(upper, region(&img, 0, nx), "the matrix's own anti-aliasing");
}

#[test]
fn a_one_storey_level_is_its_picture_alone() {
    let level = builtin("corner");
    assert_eq!(level.info.storeys, 1);
    let (nx, nz) = (level.info.nx as usize, level.info.nz as usize);
    let g = game(level);
    assert_eq!(image_size(&level), (nx, nz));
    let img = game_image(&g);
    assert_eq!(img, level_picture(&g));
    assert_eq!((img.0, img.1), (nx, nz));
}

#[test]
fn compose_pads_and_never_panics() {
    // No maps: the picture as it is.
    let px = [1u8, 2, 3, 4, 5, 6];
    assert_eq!(compose((3, 2, &px), &[], 3, 2), (3, 2, px.to_vec()));
    // A taller map than the picture, and a map slice too short for its size.
    let (w, h, out) = compose((1, 1, &[7]), &[vec![9, 9], vec![8]], 1, 2);
    assert_eq!((w, h), (1 + 2 * (GAP_LEDS + 1), 2));
    assert_eq!(out[0], 7);
    assert_eq!(out[w], NO_LED, "below the shorter picture");
    assert_eq!(out[1 + GAP_LEDS], 9);
    assert_eq!(out[w + 1 + GAP_LEDS], 9);
    assert_eq!(out[2 + 2 * GAP_LEDS], 8);
    assert_eq!(
        out[w + 2 + 2 * GAP_LEDS],
        NO_LED,
        "past the short map's end"
    );
    // Empty everything.
    assert_eq!(compose((0, 0, &[]), &[], 0, 0), (0, 0, vec![]));
}

/// Runs `cargo sim -- --level NAME --autopilot --gif FILE` in-process and
/// returns the GIF's decoder (palette indices) and the file's size.
fn sim_gif(name: &str) -> (gif::Decoder<std::fs::File>, u64) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("storey_gif");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.{}.gif", std::process::id()));
    let p = path.to_str().unwrap();
    let args = Args::try_parse_from(["sim", "--level", name, "--autopilot", "--gif", p])
        .expect("arguments");
    let report = simulate(&args).expect("sim");
    assert_eq!(report.outcome, "won");
    assert!(report.gif_frames > 10, "{} GIF frames", report.gif_frames);
    let len = std::fs::metadata(&path).unwrap().len();
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let decoder = opts.read_info(std::fs::File::open(&path).unwrap()).unwrap();
    (decoder, len)
}

#[test]
fn sim_gif_of_a_one_storey_level_is_the_matrix_only() {
    let (d, _) = sim_gif("corner");
    // 9×5 tiles at 12 px each: no maps.
    assert_eq!((d.width(), d.height()), (9 * 12, 5 * 12));
}

#[test]
fn sim_gif_of_two_floors_has_the_maps() {
    let (mut d, len) = sim_gif("two-floors");
    let (nx, nz) = (11usize, 5usize);
    let w = nx + 2 * (GAP_LEDS + nx);
    assert_eq!((d.width() as usize, d.height() as usize), (w * 12, nz * 12));
    assert!(len < 1 << 20, "{len} bytes");
    // The first GIF frame is the whole image: sample the middle of LEDs.
    let f = d.read_next_frame().unwrap().expect("a first frame").clone();
    assert_eq!((f.left, f.top), (0, 0));
    assert_eq!(f.width as usize, w * 12);
    let led = |x: usize, y: usize| f.buffer[(y * 12 + 5) * w * 12 + x * 12 + 5];
    let (upper, lower) = (nx + GAP_LEDS, 2 * (nx + GAP_LEDS));
    assert_eq!(led(nx, 2), NO_LED, "the gap's palette index");
    assert_eq!(led(upper + 5, 3), WALL);
    assert_eq!(led(lower + 5, 3), FLOOR);
    assert_eq!(led(upper + 1, 1), MARBLE.min(MAX_BRIGHTNESS));
    assert_eq!(led(lower + 1, 1), WALL);
    assert_eq!(led(lower + 1, 3), GOAL_ON);
    // Later frames hold only what changed: at least one is narrower.
    let mut narrower = false;
    while let Some(f) = d.read_next_frame().unwrap() {
        narrower |= (f.width as usize) < w * 12;
    }
    assert!(narrower, "only changed rectangles after the first frame");
}
