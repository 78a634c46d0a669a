//! The host GIF's image of a game: the LED-matrix picture and, for a level of
//! several storeys, a map of every storey beside it, as QEMU's terminal shows
//! them side by side.
//!
//! ```text
//! ┌ picture ┐     ┌ storey n−1 ┐     ┌ storey n−2 ┐ … ┌ storey 0 ┐
//! │ nx × nz │ gap │  nx × nz   │ gap │  nx × nz   │ … │ nx × nz  │
//! ```
//!
//! The picture is [`level_picture`]: the whole level drawn by
//! [`crate::render`] as the matrix shows it (the followed marble's storey).
//! A one-storey level's image is that picture alone, so its GIF is unchanged.
//! With more storeys, each map is one storey's whole maze, one LED per tile,
//! top storey first (the order the level text lists them), each after a gap of
//! [`GAP_LEDS`] columns of [`NO_LED`] (drawn in the GIF's background colour,
//! not as dark LEDs). A map's tiles have the renderer's own brightness
//! ([`storey_tile`]: walls, floor, holes, the storey's goals blinking with the
//! game's frame counter), and every marble still in play is drawn on the map
//! of its storey ([`TileLayout::storey_of`] of its height; a marble falling
//! between storeys shows on the storey whose height range holds it),
//! anti-aliased by [`draw_marble`] exactly as on the matrix.
//!
//! Everything here is pure (no file): [`game_image`] is what `cargo sim --gif`
//! records, [`image_size`] the size `GifRecorder::create` is given.
//!
//! [`TileLayout::storey_of`]: crate::physics::geometry::tiles::TileLayout::storey_of

use std::vec;
use std::vec::Vec;

use super::gif_out::NO_LED;
use super::level_picture;
use crate::game::level::LevelView;
use crate::game::rules::Game;
use crate::matrix::{Frame, MAX_BRIGHTNESS};
use crate::physics::{Scalar, World};
use crate::render::{blink_on, draw_marble, storey_tile, tile_point, TilePoint, Viewport, MARBLE};

/// Columns of [`NO_LED`] before each storey map.
pub const GAP_LEDS: usize = 2;

/// An image of LEDs: `(width, height, levels)`, `levels` row-major.
pub(crate) type Image = (usize, usize, Vec<u8>);

/// Storey maps shown for `level`: none for a one-storey level, else one per
/// storey.
fn maps_of(level: &LevelView<'_>) -> usize {
    match level.info.storeys {
        0 | 1 => 0,
        n => n as usize,
    }
}

/// The size of [`compose`]'s image for a `w`×`h` picture and `maps` maps of
/// `map_w`×`map_h`.
fn composed_size(w: usize, h: usize, maps: usize, map_w: usize, map_h: usize) -> (usize, usize) {
    if maps == 0 {
        return (w, h);
    }
    (
        w.saturating_add(maps.saturating_mul(GAP_LEDS.saturating_add(map_w))),
        h.max(map_h),
    )
}

/// The size (LEDs) of every [`game_image`] of `level`: the picture's `nx`×`nz`,
/// plus a gap and an `nx`×`nz` map per storey when it has more than one.
pub fn image_size(level: &LevelView<'_>) -> (usize, usize) {
    let (nx, nz) = (level.info.nx as usize, level.info.nz as usize);
    composed_size(nx, nz, maps_of(level), nx, nz)
}

/// Lays out `picture` (`w`×`h` levels, row-major) and then each of `maps`
/// (`map_w`×`map_h` each, left to right in the order given), each map after
/// [`GAP_LEDS`] columns of [`NO_LED`]. The image is as high as the highest of
/// them; what a shorter one leaves below it is [`NO_LED`]. Without maps the
/// image is `picture` itself. A slice shorter than its size says reads as
/// [`NO_LED`] where it runs out (no panic).
pub fn compose(
    picture: (usize, usize, &[u8]),
    maps: &[Vec<u8>],
    map_w: usize,
    map_h: usize,
) -> Image {
    let (w, h, px) = picture;
    let (cw, ch) = composed_size(w, h, maps.len(), map_w, map_h);
    let mut out = vec![NO_LED; cw.saturating_mul(ch)];
    let mut blit = |x0: usize, bw: usize, bh: usize, src: &[u8]| {
        for y in 0..bh.min(ch) {
            for x in 0..bw {
                if let (Some(&v), Some(d)) = (src.get(y * bw + x), out.get_mut(y * cw + x0 + x)) {
                    *d = v;
                }
            }
        }
    };
    blit(0, w, h, px);
    let mut x0 = w;
    for map in maps {
        x0 += GAP_LEDS;
        blit(x0, map_w, map_h, map);
        x0 += map_w;
    }
    (cw, ch, out)
}

/// `storey`'s whole maze (`nx`×`nz` levels, row-major): [`storey_tile`] for
/// every tile (goals lit when `blink`), then every marble of `world` still in
/// play whose storey is `storey`, drawn by [`draw_marble`] at [`MARBLE`].
/// Storey 0 is the lowest.
pub(crate) fn storey_map<S: Scalar, const M: usize>(
    level: &LevelView<'_>,
    world: &World<'_, S, M>,
    storey: i32,
    blink: bool,
) -> Vec<u8> {
    let (w, h) = (level.info.nx as usize, level.info.nz as usize);
    let mut map = Vec::with_capacity(w * h);
    for k in 0..h as i32 {
        for i in 0..w as i32 {
            map.push(storey_tile(level, i, k, storey, blink));
        }
    }
    let layout = &world.params().layout;
    for m in world.marbles().iter().filter(|m| !m.out) {
        if layout.storey_of(m.pos.y).max(0) == storey {
            add_marble(&mut map, w, h, tile_point(layout, m.pos.x, m.pos.z));
        }
    }
    map
}

/// Adds a marble at `point` to `map` (`w`×`h`, tile `(0, 0)` at its origin):
/// [`draw_marble`] on a 3×3 frame around the marble's tile (its 2×2 pixels
/// always fall inside), then each pixel added, saturating at
/// [`MAX_BRIGHTNESS`] as on the matrix; pixels outside the map are dropped.
fn add_marble(map: &mut [u8], w: usize, h: usize, point: TilePoint) {
    let (ti, tk) = point.tile();
    let origin = Viewport::new(ti.saturating_sub(1), tk.saturating_sub(1));
    let mut stamp = Frame::<3, 3>::new();
    draw_marble(&mut stamp, point, origin, MARBLE);
    for (x, y, level) in stamp.iter() {
        let i = i64::from(origin.x) + x as i64;
        let k = i64::from(origin.z) + y as i64;
        if level == 0 || i < 0 || k < 0 || i >= w as i64 || k >= h as i64 {
            continue;
        }
        if let Some(p) = map.get_mut(k as usize * w + i as usize) {
            *p = p.saturating_add(level).min(MAX_BRIGHTNESS);
        }
    }
}

/// What `cargo sim --gif` records of `game` (see the module docs): the
/// picture alone for a one-storey level, else the picture and every storey's
/// map, top storey first. Its size is [`image_size`] of the game's level.
pub fn game_image<S: Scalar>(game: &Game<'_, S>) -> Image {
    let (w, h, px) = level_picture(game);
    let level = game.level();
    let n = maps_of(level);
    if n == 0 {
        return (w, h, px);
    }
    let blink = blink_on(game.frames(), game.config().frame_log2);
    let maps: Vec<Vec<u8>> = (0..n as i32)
        .rev()
        .map(|storey| storey_map(level, game.world(), storey, blink))
        .collect();
    let (map_w, map_h) = (level.info.nx as usize, level.info.nz as usize);
    compose((w, h, &px), &maps, map_w, map_h)
}
