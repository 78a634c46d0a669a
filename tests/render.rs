//! Host tests for the world → LED-matrix renderer.

use fixed::types::I8F24;
use marble_rolling::game::level::{parse, words_needed, Level};
use marble_rolling::game::rules::{cell_centre, Game, GameConfig};
use marble_rolling::input::tilt::GravityMg;
use marble_rolling::matrix::{Frame, MAX_BRIGHTNESS};
use marble_rolling::physics::Vec3;
use marble_rolling::render::{
    blink_on, draw_marble, drop_glow, margin, render_background, render_world, storey_tile,
    tile_point, Renderer, Viewport, DROP_FLASH, FLOOR, GOAL_OFF, GOAL_ON, HOLE, MARBLE, OUTSIDE,
    WALL,
};

type S = I8F24;

/// Occupancy words for every level in these tests (a 127×127 level needs 1009).
const WORDS: usize = 1024;

fn level(src: &str) -> Level<'_, WORDS> {
    assert!(words_needed(src) <= WORDS);
    match parse::<WORDS>(src) {
        Ok(l) => l,
        Err(e) => panic!("bad test level: {e}"),
    }
}

fn game<'a>(l: &'a Level<'a, WORDS>) -> Game<'a, S> {
    Game::<S>::new(l.view(), GameConfig::DEFAULT).expect("game")
}

/// A `n`×`n`-tile level: border walls, posts at even/even, floor elsewhere,
/// start at (1, 1), goal at the opposite corner cell.
fn big_level_text(n: usize) -> String {
    let mut s = String::from("name: big\n---\n");
    for k in 0..n {
        for i in 0..n {
            let c = if i == 0 || k == 0 || i == n - 1 || k == n - 1 || (i % 2 == 0 && k % 2 == 0) {
                '#'
            } else if i == 1 && k == 1 {
                'S'
            } else if i == n - 2 && k == n - 2 {
                'G'
            } else {
                '.'
            };
            s.push(c);
        }
        s.push('\n');
    }
    s
}

/// Places marble `n` at `(x, z)` pitches.
fn place(g: &mut Game<'_, S>, n: usize, x: S, z: S) {
    let m = &mut g.world_mut().marbles_mut()[n];
    m.pos = Vec3::new(x, m.pos.y, z);
}

/// The boundary between tile `i` and tile `i + 1` along an axis (pitches).
fn boundary(g: &Game<'_, S>, i: i32) -> S {
    g.world().params().layout.span_xz(i).1
}

/// Per-pixel `frame − background` (saturated pixels count what was added).
fn added<const W: usize, const H: usize>(
    frame: &Frame<W, H>,
    bg: &Frame<W, H>,
) -> Vec<(usize, usize, u8)> {
    frame
        .iter()
        .filter_map(|(x, y, v)| {
            let b = bg.get(x, y);
            assert!(v >= b, "marble darkened ({x}, {y})");
            (v > b).then_some((x, y, v - b))
        })
        .collect()
}

/// A deterministic pseudo-random stream (xorshift).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in `[0, hi)` pitches, in I8F24 LSBs.
    fn pitch(&mut self, hi: S) -> S {
        S::from_bits((self.next() % hi.to_bits() as u64) as i32)
    }
}

const CORRIDOR: &str = "---\n#######\n#S.O.G#\n#######\n";

#[test]
fn tile_kinds_get_their_levels() {
    let l = level(CORRIDOR);
    let v = l.view();
    // 7×3 tiles on 8×8: columns centred at offset 0 (odd pixel right), rows at 2.
    let on: Frame<8, 8> = render_background(&v, 0, true, Viewport::new(0, -2));
    let off: Frame<8, 8> = render_background(&v, 0, false, Viewport::new(0, -2));
    let row = |f: &Frame<8, 8>, y| (0..8).map(|x| f.get(x, y)).collect::<Vec<_>>();
    assert_eq!(
        row(&on, 2),
        vec![WALL; 7]
            .into_iter()
            .chain([OUTSIDE])
            .collect::<Vec<_>>()
    );
    assert_eq!(
        row(&on, 3),
        vec![WALL, FLOOR, FLOOR, HOLE, FLOOR, GOAL_ON, WALL, OUTSIDE]
    );
    assert_eq!(
        row(&off, 3),
        vec![WALL, FLOOR, FLOOR, HOLE, FLOOR, GOAL_OFF, WALL, OUTSIDE]
    );
    for y in [0, 1, 5, 6, 7] {
        assert_eq!(row(&on, y), vec![OUTSIDE; 8], "row {y}");
    }
    // The same through a Renderer on the game, marble at S drawn on its floor pixel.
    let g = game(&l);
    let f: Frame<8, 8> = Renderer::new().render(&g);
    assert_eq!(
        row(&f, 3),
        vec![
            WALL,
            MAX_BRIGHTNESS,
            FLOOR,
            HOLE,
            FLOOR,
            GOAL_ON,
            WALL,
            OUTSIDE
        ]
    );
    assert_eq!(f.get(1, 3), (FLOOR + MARBLE).min(MAX_BRIGHTNESS));
}

#[test]
fn marble_at_cell_centre_lights_one_pixel_fully() {
    let src = big_level_text(41);
    let l = level(&src);
    let mut g = game(&l);
    for &(i, k) in &[(1u8, 1u8), (3, 5), (19, 21), (39, 39)] {
        let (x, z) = cell_centre(g.world().params(), i, k);
        place(&mut g, 0, x, z);
        let p = tile_point(&g.world().params().layout, x, z);
        assert_eq!((p.u, p.v), (i as i32 * 64 + 32, k as i32 * 64 + 32));
        let vp = Viewport::new(i as i32 - 2, k as i32 - 2);
        let mut blank = Frame::<5, 5>::new();
        draw_marble(&mut blank, p, vp, MARBLE);
        let lit: Vec<_> = blank.iter().filter(|p| p.2 > 0).collect();
        assert_eq!(lit, vec![(2, 2, MARBLE)], "cell ({i}, {k})");
        let f: Frame<5, 5> = render_world(g.level(), g.world(), true, vp);
        let bg: Frame<5, 5> = render_background(g.level(), 0, true, vp);
        assert_eq!(f.get(2, 2), MAX_BRIGHTNESS);
        let diff = added(&f, &bg);
        assert_eq!(diff.len(), 1, "{diff:?}");
    }
}

#[test]
fn marble_between_two_pixels_splits_its_brightness() {
    let src = big_level_text(41);
    let l = level(&src);
    let mut g = game(&l);
    // Pixel centres of a cell (tile 5) and the wall after it (tile 6) are half a
    // pixel either side of the tile boundary: the marble there splits 8 + 7.
    let (_, z) = cell_centre(g.world().params(), 5, 5);
    let x = boundary(&g, 5);
    place(&mut g, 0, x, z);
    let vp = Viewport::new(3, 3);
    let mut blank = Frame::<5, 5>::new();
    draw_marble(
        &mut blank,
        tile_point(&g.world().params().layout, x, z),
        vp,
        MARBLE,
    );
    let (a, b) = (blank.get(2, 2), blank.get(3, 2));
    assert!(a.abs_diff(b) <= 1 && a + b == MARBLE, "{a} + {b}");
    assert_eq!(blank.iter().filter(|p| p.2 > 0).count(), 2);
    // On the real background (floor 1, wall 3) nothing saturates: sum 15 ± 1.
    let f: Frame<5, 5> = render_world(g.level(), g.world(), true, vp);
    let bg: Frame<5, 5> = render_background(g.level(), 0, true, vp);
    let diff = added(&f, &bg);
    let sum: u32 = diff.iter().map(|d| d.2 as u32).sum();
    assert_eq!(diff.len(), 2, "{diff:?}");
    assert!(sum.abs_diff(MARBLE as u32) <= 1, "{diff:?}");
    assert_eq!((diff[0].0, diff[0].1, diff[1].0, diff[1].1), (2, 2, 3, 2));
    // Halfway in both axes: four pixels, about a quarter each.
    let zb = boundary(&g, 5);
    place(&mut g, 0, x, zb);
    let mut blank = Frame::<5, 5>::new();
    draw_marble(
        &mut blank,
        tile_point(&g.world().params().layout, x, zb),
        vp,
        MARBLE,
    );
    let lit: Vec<_> = blank.iter().filter(|p| p.2 > 0).map(|p| p.2).collect();
    assert_eq!(lit.len(), 4);
    assert_eq!(lit.iter().map(|&v| v as u32).sum::<u32>(), MARBLE as u32);
    assert!(lit.iter().all(|&v| (3..=4).contains(&v)), "{lit:?}");
}

#[test]
fn motion_across_a_tile_is_smooth_and_conserves_brightness() {
    let src = big_level_text(41);
    let l = level(&src);
    let g = game(&l);
    let layout = g.world().params().layout;
    let (_, z) = cell_centre(g.world().params(), 5, 5);
    let vp = Viewport::new(0, 3);
    // Sweep x' across two pitches in small steps: the brightness-weighted column
    // moves monotonically and the total stays exactly MARBLE.
    let mut last_centroid = 0u32;
    let start = S::from_num(2.6);
    for n in 0..200 {
        let x = start + S::from_num(n as f64 * 0.01);
        let mut f = Frame::<16, 5>::new();
        draw_marble(&mut f, tile_point(&layout, x, z), vp, MARBLE);
        let total: u32 = f.iter().map(|p| p.2 as u32).sum();
        assert_eq!(total, MARBLE as u32, "x = {x}");
        let centroid: u32 = f.iter().map(|p| p.2 as u32 * p.0 as u32 * 64).sum::<u32>() / total;
        assert!(
            centroid + 8 >= last_centroid,
            "x = {x}: {centroid} after {last_centroid}"
        );
        last_centroid = centroid;
    }
}

#[test]
fn goal_blinks_at_two_hertz() {
    // 128 frames/s: 32 frames lit, 32 dark.
    for f in 0..256u32 {
        assert_eq!(blink_on(f, 7), (f / 32) % 2 == 0, "frame {f}");
    }
    // 64 frames/s: 16 and 16.
    assert!(blink_on(15, 6) && !blink_on(16, 6) && blink_on(32, 6));
    // Below 4 frames/s: toggles every frame; never panics.
    assert!(blink_on(0, 0) && !blink_on(1, 0) && !blink_on(1, 1));
    assert!(blink_on(u32::MAX - 1, 40) || !blink_on(u32::MAX - 1, 40));

    // Through a game: the goal pixel is on in some frames, off in others, at the
    // documented rate, and deterministically so.
    let l = level(CORRIDOR);
    let mut g = game(&l);
    let mut r = Renderer::<8, 8>::new();
    let mut seen = Vec::new();
    for _ in 0..130 {
        let f = r.render(&g);
        seen.push(f.get(5, 3));
        g.frame();
    }
    assert_eq!(g.frames(), 130, "the marble should rest on a flat board");
    for (n, &v) in seen.iter().enumerate() {
        let want = if (n / 32) % 2 == 0 { GOAL_ON } else { GOAL_OFF };
        assert_eq!(v, want, "frame {n}");
    }
}

#[test]
fn fallen_marble_is_not_drawn() {
    let l = level("---\n#########\n#S.S...G#\n#########\n");
    let mut g = game(&l);
    let vp = Viewport::new(0, -1);
    let bg: Frame<9, 5> = render_background(g.level(), 0, true, vp);
    let both: Frame<9, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(added(&both, &bg).len(), 2);
    g.world_mut().marbles_mut()[0].out = true;
    let one: Frame<9, 5> = render_world(g.level(), g.world(), true, vp);
    let d = added(&one, &bg);
    assert_eq!(d.len(), 1);
    assert_eq!((d[0].0, d[0].1), (3, 2));
    g.world_mut().marbles_mut()[1].out = true;
    let none: Frame<9, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(none, bg);
    // The renderer keeps a sensible view with nobody in play.
    let f: Frame<9, 5> = Renderer::new().render(&g);
    assert_eq!(f, bg);
}

#[test]
fn brightness_saturates_never_wraps() {
    let l = level("---\n#########\n#S.S...G#\n#########\n");
    let mut g = game(&l);
    // Both marbles on the goal cell's centre: 8 + 15 + 15 saturates at 15.
    let (x, z) = cell_centre(g.world().params(), 7, 1);
    place(&mut g, 0, x, z);
    place(&mut g, 1, x, z);
    let vp = Viewport::new(0, -1);
    let f: Frame<9, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(f.get(7, 2), MAX_BRIGHTNESS);
    let mut rng = Rng(0x5eed);
    let (ex, ez) = g.world().extent();
    for _ in 0..500 {
        for n in 0..2 {
            let (x, z) = (rng.pitch(ex), rng.pitch(ez));
            place(&mut g, n, x, z);
        }
        let f: Frame<9, 5> = render_world(g.level(), g.world(), true, vp);
        assert!(f.iter().all(|p| p.2 <= MAX_BRIGHTNESS));
        let mut blank = Frame::<9, 5>::new();
        for m in g.world().marbles() {
            draw_marble(
                &mut blank,
                tile_point(&g.world().params().layout, m.pos.x, m.pos.z),
                vp,
                MARBLE,
            );
        }
        assert!(blank.iter().all(|p| p.2 <= MAX_BRIGHTNESS));
    }
}

/// Random positions across a 41×41 maze: the viewport keeps the marble's
/// whole 2×2 footprint on screen, its tile at least `margin` from an edge
/// unless the view is clamped at the maze's edge, and always inside the maze.
fn viewport_follows<const W: usize, const H: usize>() {
    let src = big_level_text(41);
    let l = level(&src);
    let mut g = game(&l);
    let (ex, ez) = g.world().extent();
    let layout = g.world().params().layout;
    let mut r = Renderer::<W, H>::new();
    let mut rng = Rng(0x1234_5678 ^ (W * 100 + H) as u64);
    let check = |r: &Renderer<W, H>, g: &Game<'_, S>| {
        let m = g.world().marbles()[0];
        let p = tile_point(&layout, m.pos.x, m.pos.z);
        let (c, k) = p.tile();
        let vp = r.viewport();
        for (o, t, size) in [(vp.x, c, W as i32), (vp.z, k, H as i32)] {
            assert!(o >= 0 && o + size <= 41, "{vp:?} outside the maze");
            let m = margin(size);
            assert!(m >= 1);
            assert!(
                t - o >= m || o == 0,
                "{t} too close to the low edge of {vp:?}"
            );
            assert!(
                o + size - 1 - t >= m || o + size == 41,
                "{t} too close to the high edge of {vp:?}"
            );
        }
        // Its brightest pixel is always on screen, and so is its whole footprint
        // unless part of that lies beyond the maze (the outer half of a border tile).
        let (sc, sk) = (c - vp.x, k - vp.z);
        assert!(
            (0..W as i32).contains(&sc) && (0..H as i32).contains(&sk),
            "{p:?} off {vp:?}"
        );
        let inner = |t: i32| (32..41 * 64 - 32).contains(&t);
        if inner(p.u) && inner(p.v) {
            let mut blank = Frame::<W, H>::new();
            draw_marble(&mut blank, p, vp, MARBLE);
            let total: u32 = blank.iter().map(|p| p.2 as u32).sum();
            assert_eq!(
                total, MARBLE as u32,
                "marble partly off screen at {p:?} with {vp:?}"
            );
        }
    };
    // Jumps anywhere.
    for _ in 0..400 {
        place(&mut g, 0, rng.pitch(ex), rng.pitch(ez));
        let f = r.render(&g);
        assert_eq!(
            f,
            render_world(g.level(), g.world(), blink_on(0, 7), r.viewport())
        );
        check(&r, &g);
    }
    // A random walk in small steps: the view scrolls at most a pixel per frame
    // and only when the marble nears an edge (dead band).
    let step = S::from_num(0.05);
    let (mut x, mut z) = cell_centre(g.world().params(), 21, 21);
    place(&mut g, 0, x, z);
    r.render(&g);
    check(&r, &g);
    let mut still = 0;
    for _ in 0..3000 {
        let d = |v: u64| match v % 3 {
            0 => -step,
            1 => S::ZERO,
            _ => step,
        };
        x = Ord::clamp(x + d(rng.next()), S::from_num(0.1), ex - S::from_num(0.1));
        z = Ord::clamp(z + d(rng.next()), S::from_num(0.1), ez - S::from_num(0.1));
        let before = r.viewport();
        place(&mut g, 0, x, z);
        r.render(&g);
        let after = r.viewport();
        assert!((after.x - before.x).abs() <= 1 && (after.z - before.z).abs() <= 1);
        if after == before {
            still += 1;
        }
        check(&r, &g);
    }
    assert!(
        still > 1500,
        "the view should mostly stand still, moved {} times",
        3000 - still
    );
}

#[test]
fn viewport_follows_on_5x5() {
    viewport_follows::<5, 5>();
}

#[test]
fn viewport_follows_on_8x8() {
    viewport_follows::<8, 8>();
}

#[test]
fn viewport_follows_on_16x9() {
    viewport_follows::<16, 9>();
}

fn viewport_clamps<const W: usize, const H: usize>() {
    let src = big_level_text(41);
    let l = level(&src);
    let mut g = game(&l);
    let mut r = Renderer::<W, H>::new();
    let f = r.render(&g);
    // Start cell (1, 1): clamped at the top-left corner, marble on pixel (1, 1).
    assert_eq!(r.viewport(), Viewport::new(0, 0));
    assert_eq!(f.get(0, 0), WALL);
    assert_eq!(f.get(1, 1), MAX_BRIGHTNESS);
    // The goal corner: clamped at the bottom-right.
    let (x, z) = cell_centre(g.world().params(), 39, 39);
    place(&mut g, 0, x, z);
    let f = r.render(&g);
    let (w, h) = (W as i32, H as i32);
    assert_eq!(r.viewport(), Viewport::new(41 - w, 41 - h));
    assert_eq!(f.get(W - 1, H - 1), WALL);
    assert_eq!(f.get(W - 2, H - 2), MAX_BRIGHTNESS);
    // Beyond the maze (rolling off an open edge): still clamped.
    place(&mut g, 0, S::from_num(40), S::from_num(-3));
    r.render(&g);
    assert_eq!(r.viewport(), Viewport::new(41 - w, 0));
    // A fresh renderer centres on the marble when it can.
    let (x, z) = cell_centre(g.world().params(), 21, 21);
    place(&mut g, 0, x, z);
    let mut fresh = Renderer::<W, H>::new();
    fresh.render(&g);
    assert_eq!(fresh.viewport(), Viewport::new(21 - w / 2, 21 - h / 2));
}

#[test]
fn viewport_clamps_at_maze_edges() {
    viewport_clamps::<5, 5>();
    viewport_clamps::<8, 8>();
    viewport_clamps::<16, 9>();
}

#[test]
fn small_maze_is_centred() {
    let l = level("---\n#####\n#S.G#\n#####\n");
    let g = game(&l);
    // 5×3 tiles on 8×8: one blank column left, two right; two rows above, three below.
    let mut r8 = Renderer::<8, 8>::new();
    let f = r8.render(&g);
    assert_eq!(r8.viewport(), Viewport::new(-1, -2));
    for (x, y, v) in f.iter() {
        let inside = (1..6).contains(&x) && (2..5).contains(&y);
        assert_eq!(v > 0, inside, "({x}, {y}) = {v}");
    }
    assert_eq!(f.get(2, 3), MAX_BRIGHTNESS);
    assert_eq!(f.get(3, 3), FLOOR);
    assert_eq!(f.get(4, 3), GOAL_ON);
    // On 5×5 the width fits exactly; on 16×9 both axes are centred.
    let mut r5 = Renderer::<5, 5>::new();
    r5.render(&g);
    assert_eq!(r5.viewport(), Viewport::new(0, -1));
    let mut r16 = Renderer::<16, 9>::new();
    let f = r16.render(&g);
    assert_eq!(r16.viewport(), Viewport::new(-5, -3));
    assert_eq!(f.iter().filter(|p| p.2 > 0).count(), 15);
    // Centred whatever the marble does.
    let mut g = g;
    place(&mut g, 0, S::from_num(2.4), S::from_num(0.5));
    r16.render(&g);
    assert_eq!(r16.viewport(), Viewport::new(-5, -3));
}

#[test]
fn mixed_axes_follow_one_and_centre_the_other() {
    // 41 tiles wide, 3 tall, on 8×8: x follows, z is centred.
    let mut src = String::from("---\n");
    src.push_str(&"#".repeat(41));
    src.push_str("\n#S");
    src.push_str(&".".repeat(37));
    src.push_str("G#\n");
    src.push_str(&"#".repeat(41));
    src.push('\n');
    let l = level(&src);
    let mut g = game(&l);
    let mut r = Renderer::<8, 8>::new();
    r.render(&g);
    assert_eq!(r.viewport(), Viewport::new(0, -2));
    let (x, z) = cell_centre(g.world().params(), 19, 1);
    place(&mut g, 0, x, z);
    r.render(&g);
    let vp = r.viewport();
    assert_eq!(vp.z, -2);
    assert!(
        (19 - vp.x) >= margin(8) && (vp.x + 7 - 19) >= margin(8),
        "{vp:?}"
    );
}

#[test]
fn rendering_is_deterministic() {
    let src = big_level_text(41);
    let l = level(&src);
    let run = || {
        let mut g = game(&l);
        let mut r = Renderer::<5, 5>::new();
        let mut frames = Vec::new();
        g.set_gravity_mg(GravityMg::new(120, -990, 80));
        for _ in 0..300 {
            g.frame();
            frames.push(r.render(&g));
        }
        frames
    };
    let a = run();
    let b = run();
    assert_eq!(a, b);
    // The marble actually rolled and the picture changed.
    assert!(a.windows(2).any(|w| w[0] != w[1]));
    // Rendering twice without stepping gives the same frame.
    let g = game(&l);
    let mut r = Renderer::<16, 9>::new();
    assert_eq!(r.render(&g), r.render(&g));
}

/// Two storeys (top first): the start above a hole at (3, 1), a post at (5, 1)
/// on the lower storey, which has the goal at (1, 1).
const TWO_STOREYS: &str = "---
#######
#S.O..#
#######
===
#######
#G..#.#
#######
";

/// The height (pitches) of a marble resting on storey `n`'s floor.
fn resting_height(g: &Game<'_, S>, n: i32) -> S {
    let p = g.world().params();
    p.layout.span_y(2 * n).1 + p.radius
}

#[test]
fn the_matrix_shows_the_followed_marble_storey() {
    let l = level(TWO_STOREYS);
    let mut g = game(&l);
    let vp = Viewport::new(0, -1);
    let top: Frame<7, 5> = render_background(g.level(), 1, true, vp);
    let low: Frame<7, 5> = render_background(g.level(), 0, true, vp);
    // Row 2 of the view is row k = 1 of the maze.
    assert_eq!(top.get(3, 2), HOLE, "the top storey's hole");
    assert_eq!(top.get(5, 2), FLOOR);
    assert_eq!(top.get(1, 2), FLOOR, "the goal is on the lower storey");
    assert_eq!(low.get(3, 2), FLOOR, "under the hole is floor");
    assert_eq!(low.get(4, 2), WALL, "the lower storey's post");
    assert_eq!(low.get(1, 2), GOAL_ON);
    assert_eq!(storey_tile(g.level(), 4, 1, 0, true), WALL);
    assert_eq!(storey_tile(g.level(), 4, 1, 1, true), FLOOR);
    assert_eq!(storey_tile(g.level(), 4, 1, 7, true), HOLE, "no storey 7");
    assert_eq!(storey_tile(g.level(), -1, 1, 0, true), OUTSIDE);

    // The marble starts on the top storey: its storey is on show, with it.
    let f: Frame<7, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(added(&f, &top), vec![(1, 2, MARBLE - FLOOR)]);
    // Moved onto the lower storey's floor: that storey is on show.
    let y = resting_height(&g, 0);
    let m = &mut g.world_mut().marbles_mut()[0];
    m.pos = Vec3::new(m.pos.x, y, m.pos.z);
    let f: Frame<7, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(added(&f, &low).len(), 1);
    assert_eq!(f.get(1, 2), MAX_BRIGHTNESS, "the marble on the goal");
}

#[test]
fn only_marbles_on_the_storey_on_show_are_drawn() {
    let l = level("---\n#######\n#S.O.S#\n#######\n===\n#######\n#G....#\n#######\n");
    let mut g = game(&l);
    let vp = Viewport::new(0, -1);
    let top: Frame<7, 5> = render_background(g.level(), 1, true, vp);
    let f: Frame<7, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(added(&f, &top).len(), 2, "both marbles on the top storey");
    // Marble 1 drops to the lower storey: the view follows marble 0 and
    // shows only it.
    let y = resting_height(&g, 0);
    let m = &mut g.world_mut().marbles_mut()[1];
    m.pos = Vec3::new(m.pos.x, y, m.pos.z);
    let f: Frame<7, 5> = render_world(g.level(), g.world(), true, vp);
    assert_eq!(added(&f, &top), vec![(1, 2, MARBLE - FLOOR)]);
}

#[test]
fn drop_glow_fades_over_a_quarter_second() {
    // 128 frames/s: 32 frames, from DROP_FLASH down, never rising.
    assert_eq!(drop_glow(0, 7), DROP_FLASH);
    assert_eq!(drop_glow(32, 7), 0);
    assert_eq!(drop_glow(u32::MAX, 7), 0);
    let mut last = DROP_FLASH;
    for e in 0..32 {
        let g = drop_glow(e, 7);
        assert!(g <= last && (e < 27 || g <= 1), "frame {e}: {g}");
        last = g;
    }
    assert!(drop_glow(16, 7) == DROP_FLASH / 2);
    // Slow frame rates: one frame; absurd ones never panic.
    assert_eq!((drop_glow(0, 2), drop_glow(1, 2)), (DROP_FLASH, 0));
    assert_eq!(drop_glow(0, 0), DROP_FLASH);
    assert!(drop_glow(1 << 20, 60) <= DROP_FLASH);
}

#[test]
fn a_drop_flashes_the_floor_it_lands_on() {
    let l = level(TWO_STOREYS);
    let mut g = game(&l);
    let mut r = Renderer::<7, 5>::new();
    let layout = g.world().params().layout;
    // The marble starts beside the hole: put it over the hole and let it fall
    // on a level board.
    let (x, _) = cell_centre(g.world().params(), 3, 1);
    let z = g.world().marbles()[0].pos.z;
    place(&mut g, 0, x, z);
    let mut floors = Vec::new();
    let mut landed_at = None;
    for n in 0..120u32 {
        let f = r.render(&g);
        let storey = layout.storey_of(g.world().marbles()[0].pos.y);
        if storey == 0 && landed_at.is_none() {
            landed_at = Some(n);
        }
        // (5, 1) is floor on both storeys and the marble never comes near.
        floors.push((storey, f.get(5, 2)));
        g.frame();
    }
    let at = landed_at.expect("the marble should drop a storey") as usize;
    assert!(at > 0);
    assert!(
        floors[..at].iter().all(|&(s, v)| s == 1 && v == FLOOR),
        "no flash before: {floors:?}"
    );
    assert_eq!(floors[at].1, FLOOR + DROP_FLASH, "the flash");
    assert!(floors[at].1 > WALL, "brighter than the walls at first");
    for (e, &(s, v)) in floors[at..].iter().enumerate() {
        assert_eq!(s, 0, "the marble stays below");
        assert_eq!(
            v,
            FLOOR + drop_glow(e as u32, 7),
            "frame {e} after the drop"
        );
    }
    assert_eq!(floors[at + 32].1, FLOOR, "over after a quarter second");

    // A restart puts the marble back up: no flash.
    g.restart();
    let f = r.render(&g);
    assert_eq!(layout.storey_of(g.world().marbles()[0].pos.y), 1);
    assert_eq!(f.get(5, 2), FLOOR);
}
