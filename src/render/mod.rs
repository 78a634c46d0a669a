//! World → LED-matrix frame: one pixel per tile, any matrix size.
//!
//! Pixel `(x, y)` shows tile `(i, k) = (viewport.x + x, viewport.z + y)`:
//!
//! | what | level |
//! |------|-------|
//! | wall (a tile in layer `j = 1`) | [`WALL`] |
//! | floor | [`FLOOR`] |
//! | hole (no floor tile) | [`HOLE`] |
//! | goal cell, blinking at [`BLINK_HZ`] | [`GOAL_ON`] / [`GOAL_OFF`] |
//! | outside the maze (a small maze is centred) | [`OUTSIDE`] |
//! | marble, added on top and saturating at 15 | [`MARBLE`] in total |
//!
//! # Storeys
//!
//! The matrix shows one storey: the one holding the marble the view follows
//! (its wall layer `j = 2n + 1` over its slab `j = 2n`, eq. 5). A hole shows
//! dark whatever lies below it, so a 5×5 view stays as readable as on a
//! one-storey level. When the followed marble drops to a lower storey, the
//! [`Renderer`] flashes the new storey's floor: it is drawn [`DROP_FLASH`]
//! levels brighter, fading linearly back to [`FLOOR`] over a quarter second
//! ([`drop_glow`]). Brighter than the walls at first, the floor tells the
//! player at a glance that the maze changed under the marble; the fade keeps
//! the walls readable again before the marble reaches one. Climbing back (a
//! restart) does not flash.
//!
//! # The marble, anti-aliased
//!
//! Tiles are not equally wide (a short wall `s ≈ 1/6` pitch, a long cell
//! `l ≈ 5/6`), but pixels are. The marble's `x'` is therefore mapped to a
//! continuous *tile-index* coordinate `u`, where tile `i` spans `[i, i + 1)`:
//! `u = i + (x' − lo_i) / (hi_i − lo_i)`. The quotient is found by bisection
//! (`SUBPIXEL_BITS` halvings and compares of the tile's width) rather than by
//! a division or a per-level reciprocal: it costs a few shifts per axis, is
//! exact at a cell's centre, and cannot overflow however thin the walls are.
//! The result is a [`TilePoint`] in 1/64 tile.
//!
//! Pixel `p`'s centre is at `u = p + ½`; the marble's [`MARBLE`] brightness is
//! split bilinearly over the 2×2 pixels around it. The four shares are rounded
//! cumulatively, so they always sum to exactly [`MARBLE`] (before the
//! saturation at [`MAX_BRIGHTNESS`]). Marbles that are out of play are not
//! drawn.
//!
//! # Viewport
//!
//! Along an axis where the maze is no larger than the matrix the maze is
//! centred. Where it is larger, the view follows marble 0 (or, once it is out,
//! the first marble still in play) with a dead band: it scrolls only when the
//! marble's tile comes within [`margin`] pixels of an edge (at least 1 pixel
//! whenever the matrix is 3 or more pixels wide), and it is clamped to the
//! maze's bounds. Scrolling is by whole pixels.
//!
//! Everything per frame is integer adds, shifts, compares and small multiplies
//! plus, per marble, a handful of [`Scalar`] shifts and compares: no division,
//! no floating point (with a fixed-point `S`), no allocation, no panics.

mod palette;
pub mod race;
pub mod screens;

pub use palette::*;

use crate::game::level::LevelView;
use crate::game::rules::Game;
use crate::matrix::{Brightness, Frame, MAX_BRIGHTNESS};
use crate::physics::geometry::tiles::{TileIndex, TileLayout};
use crate::physics::world::World;
use crate::physics::Scalar;

/// Fraction bits of a [`TilePoint`] (1/64 tile).
pub(crate) const SUBPIXEL_BITS: u32 = 6;
/// One tile in [`TilePoint`] units.
pub(crate) const SUBPIXEL_ONE: i32 = 1 << SUBPIXEL_BITS;

/// The tile shown at pixel `(0, 0)`; negative when a small maze is centred.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Viewport {
    /// Tile column `i` at pixel column 0.
    pub x: i32,
    /// Tile row `k` at pixel row 0.
    pub z: i32,
}

impl Viewport {
    /// The viewport whose pixel `(0, 0)` shows tile `(x, z)`.
    pub const fn new(x: i32, z: i32) -> Self {
        Viewport { x, z }
    }
}

/// A point in tile-index space, in 1/`SUBPIXEL_ONE` tile: tile `i` spans
/// `[i·64, (i + 1)·64)` along `u` (x') and likewise along `v` (z').
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TilePoint {
    /// Along x' (tile columns).
    pub u: i32,
    /// Along z' (tile rows).
    pub v: i32,
}

impl TilePoint {
    /// The tile holding the point (`⌊u⌋`, `⌊v⌋`).
    pub const fn tile(&self) -> (i32, i32) {
        (self.u >> SUBPIXEL_BITS, self.v >> SUBPIXEL_BITS)
    }
}

/// One axis of [`tile_point`]: `i·64 + ⌊64·(a − lo_i)/(hi_i − lo_i)⌋` by bisection.
fn axis_point<S: Scalar>(layout: &TileLayout<S>, a: S) -> i32 {
    let i = layout.index_xz(a);
    let (lo, hi) = layout.span_xz(i);
    let mut rest = a - lo;
    let mut width = hi - lo;
    let mut t = 0i32;
    let mut bit = SUBPIXEL_BITS;
    while bit > 0 {
        bit -= 1;
        width = width.half();
        if width > S::ZERO && rest >= width {
            rest -= width;
            t |= 1 << bit;
        }
    }
    i.saturating_mul(SUBPIXEL_ONE).saturating_add(t)
}

/// Where the tile-frame point `(x', z')` (pitches) lies in tile-index space,
/// mapped through the uneven short/long tile widths.
pub fn tile_point<S: Scalar>(layout: &TileLayout<S>, x: S, z: S) -> TilePoint {
    TilePoint {
        u: axis_point(layout, x),
        v: axis_point(layout, z),
    }
}

/// How close (pixels) the followed marble's tile may come to an edge of a
/// `size`-pixel axis before the view scrolls: `max(1, size / 4)`, or 0 on
/// axes narrower than 3 pixels.
pub const fn margin(size: i32) -> i32 {
    if size < 3 {
        0
    } else if size >> 2 > 1 {
        size >> 2
    } else {
        1
    }
}

/// One axis of the viewport: `tiles` tiles on `size` pixels, following tile
/// `focus` (if any) from the previous origin `current` (`None`: start fresh,
/// centred on the focus).
pub(crate) fn follow_axis(current: Option<i32>, tiles: i32, size: i32, focus: Option<i32>) -> i32 {
    if tiles <= size {
        // Centred; the odd pixel (if any) goes to the right / bottom.
        return -((size - tiles) >> 1);
    }
    let max = tiles - size;
    let m = margin(size);
    let mut origin = match (current, focus) {
        (Some(o), _) => o,
        (None, Some(c)) => c - (size >> 1),
        (None, None) => 0,
    };
    if let Some(c) = focus {
        if c < origin + m {
            origin = c - m;
        } else if c > origin + size - 1 - m {
            origin = c - (size - 1 - m);
        }
    }
    origin.clamp(0, max)
}

/// `usize` → `i32`, saturating (matrix sizes).
const fn to_i32(n: usize) -> i32 {
    if n > i32::MAX as usize {
        i32::MAX
    } else {
        n as i32
    }
}

/// The point the viewport follows: marble 0, or the first marble still in play.
fn focus<S: Scalar, const M: usize>(world: &World<'_, S, M>) -> Option<TilePoint> {
    let layout = &world.params().layout;
    world
        .marbles()
        .iter()
        .find(|m| !m.out)
        .map(|m| tile_point(layout, m.pos.x, m.pos.z))
}

/// The storey on show: the focus marble's (the lowest before any marble is
/// placed, or once all are out).
fn focus_storey<S: Scalar, const M: usize>(world: &World<'_, S, M>) -> i32 {
    if !cfg!(feature = "storeys") {
        return 0;
    }
    let layout = &world.params().layout;
    world
        .marbles()
        .iter()
        .find(|m| !m.out)
        .map_or(0, |m| layout.storey_of(m.pos.y).max(0))
}

/// The brightness of tile `(i, k)` of `storey` without marbles: a goal of that
/// storey, else its wall layer, then its floor slab (eq. 5: layers
/// `2·storey + 1` and `2·storey`); outside the maze [`OUTSIDE`]. Any tile
/// index is safe. Maps of a whole storey (QEMU's terminal, the host's GIF)
/// use it, so they show what the matrix would.
pub fn storey_tile(
    level: &LevelView<'_>,
    i: i32,
    k: i32,
    storey: i32,
    blink_on: bool,
) -> Brightness {
    tile_level(level, i, k, storey, blink_on)
}

/// [`storey_tile`], inlined into [`render_background`]'s loop: with a second
/// caller (the storey maps) LLVM left it out of line, a call per pixel that
/// cost QEMU's demo 130 instructions per frame.
#[inline(always)]
fn tile_level(level: &LevelView<'_>, i: i32, k: i32, storey: i32, blink_on: bool) -> Brightness {
    if i < 0 || k < 0 || i >= level.info.nx as i32 || k >= level.info.nz as i32 {
        return OUTSIDE;
    }
    let storey = if cfg!(feature = "storeys") { storey } else { 0 };
    let is_goal = level.info.goals().iter().any(|goal| {
        i32::from(goal.i) == i && i32::from(goal.k) == k && i32::from(goal.storey) == storey
    });
    if is_goal {
        if blink_on {
            GOAL_ON
        } else {
            GOAL_OFF
        }
    } else if level.tiles.is_solid(TileIndex::new(i, 2 * storey + 1, k)) {
        WALL
    } else if level.tiles.is_solid(TileIndex::new(i, 2 * storey, k)) {
        FLOOR
    } else {
        HOLE
    }
}

/// The tiles of `storey` alone (walls, floor, holes, goals, outside), without
/// marbles.
pub fn render_background<const W: usize, const H: usize>(
    level: &LevelView<'_>,
    storey: i32,
    blink_on: bool,
    viewport: Viewport,
) -> Frame<W, H> {
    let mut frame = Frame::new();
    let mut k = viewport.z;
    for y in 0..H {
        let mut i = viewport.x;
        for x in 0..W {
            frame.set(x, y, tile_level(level, i, k, storey, blink_on));
            i = i.saturating_add(1);
        }
        k = k.saturating_add(1);
    }
    frame
}

/// Adds `level` to pixel `(px, py)` (saturating); ignored outside the frame.
fn add_pixel<const W: usize, const H: usize>(
    frame: &mut Frame<W, H>,
    px: i32,
    py: i32,
    level: u32,
) {
    if px < 0 || py < 0 || level == 0 {
        return;
    }
    let (x, y) = (px as usize, py as usize);
    if x >= W || y >= H {
        return;
    }
    let add = level.min(MAX_BRIGHTNESS as u32) as Brightness;
    frame.set(x, y, frame.get(x, y).saturating_add(add));
}

/// Draws a marble of total brightness `brightness` at `point`, split
/// bilinearly over the 2×2 pixels around it and added on top of what is there
/// (saturating at [`MAX_BRIGHTNESS`]). The shares sum to exactly `brightness`
/// before saturation; pixels outside the frame are dropped.
pub fn draw_marble<const W: usize, const H: usize>(
    frame: &mut Frame<W, H>,
    point: TilePoint,
    viewport: Viewport,
    brightness: Brightness,
) {
    const HALF: i32 = SUBPIXEL_ONE >> 1;
    const MASK: i32 = SUBPIXEL_ONE - 1;
    // Pixel centres sit at `p + ½`: shift by half a pixel, then split.
    let pu = point.u.saturating_sub(HALF);
    let pv = point.v.saturating_sub(HALF);
    let (x0, fx) = (
        (pu >> SUBPIXEL_BITS).saturating_sub(viewport.x),
        (pu & MASK) as u32,
    );
    let (y0, fy) = (
        (pv >> SUBPIXEL_BITS).saturating_sub(viewport.z),
        (pv & MASK) as u32,
    );
    let one = SUBPIXEL_ONE as u32;
    let shares = [
        (0, 0, (one - fx) * (one - fy)),
        (1, 0, fx * (one - fy)),
        (0, 1, (one - fx) * fy),
        (1, 1, fx * fy),
    ];
    // Cumulative rounding: share n gets round(b·C_n) − round(b·C_{n−1}), so the
    // shares always add up to `b` exactly.
    let b = brightness.min(MAX_BRIGHTNESS) as u32;
    let shift = 2 * SUBPIXEL_BITS;
    let round = 1u32 << (shift - 1);
    let mut cumulative = 0u32;
    let mut drawn = 0u32;
    for (dx, dy, weight) in shares {
        cumulative += weight;
        let upto = (b * cumulative + round) >> shift;
        add_pixel(
            frame,
            x0.saturating_add(dx),
            y0.saturating_add(dy),
            upto - drawn,
        );
        drawn = upto;
    }
}

/// Renders `world` on `level` through `viewport`: the background of the focus
/// marble's storey (goals lit when `blink_on`) and every marble still in play
/// on it. Pure: no state, usable without a [`Game`].
pub fn render_world<S: Scalar, const M: usize, const W: usize, const H: usize>(
    level: &LevelView<'_>,
    world: &World<'_, S, M>,
    blink_on: bool,
    viewport: Viewport,
) -> Frame<W, H> {
    let storey = focus_storey(world);
    let mut frame = render_background(level, storey, blink_on, viewport);
    draw_marbles(&mut frame, world, storey, viewport);
    frame
}

/// Every marble still in play on `storey`, at full brightness, on top of
/// `frame`.
fn draw_marbles<S: Scalar, const M: usize, const W: usize, const H: usize>(
    frame: &mut Frame<W, H>,
    world: &World<'_, S, M>,
    storey: i32,
    viewport: Viewport,
) {
    let layout = &world.params().layout;
    let on_show = |y: S| {
        !cfg!(feature = "storeys")
            || world.tiles().storeys() == 1
            || layout.storey_of(y).max(0) == storey
    };
    for m in world
        .marbles()
        .iter()
        .filter(|m| !m.out && on_show(m.pos.y))
    {
        draw_marble(
            frame,
            tile_point(layout, m.pos.x, m.pos.z),
            viewport,
            MARBLE,
        );
    }
}

/// The ghost marble's total brightness (the best run raced beside the live
/// attempt, `game::ghost`): a third of [`MARBLE`], so that on a matrix of 16
/// levels the two are told apart, and the ghost still outshines a wall.
pub const GHOST: Brightness = 5;
const _: () = assert!(GHOST < MARBLE && GHOST > WALL);

/// Draws `ghost`'s marbles still in play (the ghost's game, on `live`'s level)
/// at [`GHOST`] brightness on top of `frame`, a picture of `live` through
/// `viewport`: only those on the storey on show.
pub(crate) fn draw_ghost<S: Scalar, const W: usize, const H: usize>(
    frame: &mut Frame<W, H>,
    live: &Game<'_, S>,
    ghost: &Game<'_, S>,
    viewport: Viewport,
) {
    let storey = focus_storey(live.world());
    let world = ghost.world();
    let layout = &world.params().layout;
    for m in world.marbles().iter().filter(|m| {
        !m.out
            && (!cfg!(feature = "storeys")
                || world.tiles().storeys() == 1
                || layout.storey_of(m.pos.y).max(0) == storey)
    }) {
        draw_marble(frame, tile_point(layout, m.pos.x, m.pos.z), viewport, GHOST);
    }
}

/// Renders a game on a `W`×`H` matrix, keeping a viewport that follows the
/// marble across mazes larger than the matrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Renderer<const W: usize, const H: usize> {
    /// The current viewport and the `(nx, nz)` of the level it was made for.
    state: Option<(Viewport, u8, u8)>,
    /// The last background and what it was drawn for (level identity, viewport,
    /// goal lit): the tiles only change when one of those does, so most frames
    /// copy it and draw the marbles on top instead of looking up every tile.
    background: Option<(BackgroundKey, Frame<W, H>)>,
    /// The game frame of the drop onto the storey on show (`None`: no drop
    /// onto it): the drop flash ([`drop_glow`]). The storey last on show is
    /// `background`'s.
    #[cfg(feature = "storeys")]
    dropped_at: Option<u32>,
}

/// A level's identity for the renderer's caches (its name's address and
/// length, its size): cheaper than comparing tiles.
type LevelKey = (usize, usize, u8, u8);

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct BackgroundKey {
    level: LevelKey,
    storey: i32,
    viewport: Viewport,
    blink: bool,
}

impl<const W: usize, const H: usize> Renderer<W, H> {
    /// A renderer without a viewport yet: the first frame centres the view on
    /// the marble (clamped to the maze).
    pub const fn new() -> Self {
        Renderer {
            state: None,
            background: None,
            #[cfg(feature = "storeys")]
            dropped_at: None,
        }
    }

    /// Forgets the viewport (a new level or a restart): the next frame
    /// re-centres on the marble. A level of different size does this by itself.
    pub(crate) fn reset(&mut self) {
        self.state = None;
        self.background = None;
        #[cfg(feature = "storeys")]
        {
            self.dropped_at = None;
        }
    }

    /// How much brighter the floor of `storey` is drawn in game frame `now`:
    /// a drop (the storey on show of the same level going down) starts the
    /// flash, and it fades over [`drop_glow`]'s quarter second.
    #[cfg(feature = "storeys")]
    fn glow(&mut self, level: LevelKey, storey: i32, now: u32, frame_log2: u32) -> Brightness {
        match self.background {
            Some((key, _)) if key.level == level && key.storey == storey => {}
            Some((key, _)) if key.level == level && storey < key.storey => {
                self.dropped_at = Some(now);
            }
            _ => self.dropped_at = None,
        }
        self.dropped_at
            .map_or(0, |at| drop_glow(now.wrapping_sub(at), frame_log2))
    }

    /// The viewport last used (the origin before the first frame).
    pub fn viewport(&self) -> Viewport {
        self.state.map(|(v, _, _)| v).unwrap_or_default()
    }

    /// Moves the viewport to follow the world's marble (see the module docs)
    /// and returns it.
    pub(crate) fn follow<S: Scalar, const M: usize>(
        &mut self,
        level: &LevelView<'_>,
        world: &World<'_, S, M>,
    ) -> Viewport {
        let (nx, nz) = (level.info.nx, level.info.nz);
        let current = match self.state {
            Some((v, x, z)) if x == nx && z == nz => Some(v),
            _ => None,
        };
        let target = focus(world).map(|p| p.tile());
        let viewport = Viewport {
            x: follow_axis(
                current.map(|v| v.x),
                nx as i32,
                to_i32(W),
                target.map(|t| t.0),
            ),
            z: follow_axis(
                current.map(|v| v.z),
                nz as i32,
                to_i32(H),
                target.map(|t| t.1),
            ),
        };
        self.state = Some((viewport, nx, nz));
        viewport
    }

    /// One frame of `game`: follows the marble, blinks the goal from the
    /// game's frame counter and frame rate, draws the marbles in play.
    pub fn render<S: Scalar>(&mut self, game: &Game<'_, S>) -> Frame<W, H> {
        let viewport = self.follow(game.level(), game.world());
        let blink = blink_on(game.frames(), game.config().frame_log2);
        let level = game.level();
        let storey = focus_storey(game.world());
        let level_key = (
            level.info.name.as_ptr() as usize,
            level.info.name.len(),
            level.info.nx,
            level.info.nz,
        );
        // A one-storey level cannot drop: it skips the flash's bookkeeping.
        #[cfg(feature = "storeys")]
        let glow = if level.info.storeys > 1 {
            self.glow(level_key, storey, game.frames(), game.config().frame_log2)
        } else {
            0
        };
        #[cfg(not(feature = "storeys"))]
        let glow = 0;
        let key = BackgroundKey {
            level: level_key,
            storey,
            viewport,
            blink,
        };
        let mut frame = match self.background {
            Some((k, bg)) if k == key => bg,
            _ => {
                let bg = render_background(level, storey, blink, viewport);
                self.background = Some((key, bg));
                bg
            }
        };
        if glow > 0 {
            // The flash lights the floor alone: the pixels at exactly
            // `FLOOR` (walls, holes, goals and the outside have levels of
            // their own), before the marbles are drawn.
            for y in 0..H {
                for x in 0..W {
                    if frame.get(x, y) == FLOOR {
                        frame.set(x, y, FLOOR + glow);
                    }
                }
            }
        }
        draw_marbles(&mut frame, game.world(), storey, viewport);
        frame
    }
}
