//! What the page draws and shows, read from the game in play: the LEDs, the
//! level's names, shape and tiles, the marbles and their storeys, the drop's
//! flash.

use marble_rolling::board::microbit::{HEIGHT, WIDTH};
use marble_rolling::game::level::{Cell, MAX_MARBLES};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::physics::world::World;
use marble_rolling::physics::{Fx, TileIndex};
use marble_rolling::render;

use crate::game_loop::with_app;
use crate::storage::answer;

pub(crate) type WebWorld = World<'static, Fx, MAX_MARBLES>;

/// Coordinate `axis` (0 x, 1 y, 2 z) of marble `index` in `world`, mm (0 for none).
pub(crate) fn marble_coord(world: &WebWorld, index: u32, axis: u32) -> f64 {
    let Some(marble) = world.marbles().get(index as usize) else {
        return 0.0;
    };
    let value = match axis {
        0 => marble.pos.x,
        1 => marble.pos.y,
        _ => marble.pos.z,
    };
    world.params().layout.to_mm(value)
}

/// The storey marble `index` of `world` is on, within the level's `storeys`.
pub(crate) fn storey_of(world: &WebWorld, index: u32, storeys: u8) -> u32 {
    world.marbles().get(index as usize).map_or(0, |m| {
        let storeys = i32::from(storeys).max(1);
        world
            .params()
            .layout
            .storey_of(m.pos.y)
            .clamp(0, storeys - 1) as u32
    })
}

/// Whether marble `index` of `world` is out of play (or there is none).
pub(crate) fn is_out(world: &WebWorld, index: u32) -> bool {
    world.marbles().get(index as usize).is_none_or(|m| m.out)
}

/// The LED matrix's width (the micro:bit's 5).
#[no_mangle]
pub extern "C" fn led_width() -> u32 {
    WIDTH as u32
}

/// The LED matrix's height.
#[no_mangle]
pub extern "C" fn led_height() -> u32 {
    HEIGHT as u32
}

/// Where the matrix's brightness values are (`led_width × led_height` bytes,
/// row by row, 0..=15), as the last [`tick`](crate::game_loop::tick) drew them.
#[no_mangle]
pub extern "C" fn led_ptr() -> *const u8 {
    with_app(core::ptr::null(), |app| app.led.as_ptr())
}

/// Built-in levels.
#[no_mangle]
pub extern "C" fn level_count() -> u32 {
    LEVELS.len() as u32
}

/// Built-in level `index`'s name in the answer buffer; its length (0 if none).
#[no_mangle]
pub extern "C" fn builtin_name(index: u32) -> u32 {
    match LEVELS.get(index as usize) {
        Some(level) => answer(format_args!("{}", level.info.name)),
        None => 0,
    }
}

/// 1 while the editor's level is the one in play.
#[no_mangle]
pub extern "C" fn level_is_custom() -> u32 {
    with_app(0, |app| app.is_custom_level() as u32)
}

/// The level in play: its built-in index, or the built-ins' count for the
/// editor's level.
#[no_mangle]
pub extern "C" fn level_index() -> u32 {
    with_app(0, |app| app.level_number())
}

/// The level in play's name in the answer buffer; its length.
#[no_mangle]
pub extern "C" fn level_name() -> u32 {
    with_app(0, |app| answer(format_args!("{}", app.level().info.name)))
}

/// The time limit of the level in play, seconds.
#[no_mangle]
pub extern "C" fn time_limit_s() -> u32 {
    with_app(0, |app| u32::from(app.level().info.time_limit_s))
}

/// Tile columns of the level in play.
#[no_mangle]
pub extern "C" fn level_nx() -> u32 {
    with_app(0, |app| u32::from(app.level().info.nx))
}

/// Tile rows of the level in play.
#[no_mangle]
pub extern "C" fn level_nz() -> u32 {
    with_app(0, |app| u32::from(app.level().info.nz))
}

/// Storeys of the level in play (1 for a flat maze).
#[no_mangle]
pub extern "C" fn level_storeys() -> u32 {
    with_app(1, |app| u32::from(app.level().info.storeys).max(1))
}

/// What tile `(i, k)` of storey `storey` (0 the lowest) is: 0 floor, 1 wall,
/// 2 hole, 3 goal, 4 start, 5 outside (also for a storey the level lacks).
#[no_mangle]
pub extern "C" fn tile_kind(i: u32, k: u32, storey: u32) -> u32 {
    with_app(5, |app| {
        let level = app.level();
        let info = &level.info;
        if i >= u32::from(info.nx) || k >= u32::from(info.nz) || storey >= u32::from(info.storeys) {
            return 5;
        }
        let cell = Cell::new(i as u8, k as u8, storey as u8);
        let storey = storey as i32;
        let solid = |j| {
            level
                .tiles
                .is_solid(TileIndex::new(i as i32, 2 * storey + j, k as i32))
        };
        if solid(1) {
            1
        } else if !solid(0) {
            2
        } else if info.goals().contains(&cell) {
            3
        } else if info.starts().contains(&cell) {
            4
        } else {
            0
        }
    })
}

/// The storey marble `index` is on (0 the lowest; the one whose wall layer or
/// floor slab holds its centre, as the LED view and QEMU's maps take it).
#[no_mangle]
pub extern "C" fn marble_storey(index: u32) -> u32 {
    with_app(0, |app| {
        storey_of(app.player.game().world(), index, app.level().info.storeys)
    })
}

/// How much brighter the floor is drawn `elapsed` frames after the followed
/// marble dropped to a lower storey, out of [`drop_flash`]: the LED matrix's
/// flash (`render::drop_glow`), so the page shows the drop as the board does.
#[no_mangle]
pub extern "C" fn drop_glow(elapsed: u32) -> u32 {
    with_app(0, |app| {
        u32::from(render::drop_glow(
            elapsed,
            app.player.game().config().frame_log2,
        ))
    })
}

/// The drop flash's full strength ([`drop_glow`] right after a drop).
#[no_mangle]
pub extern "C" fn drop_flash() -> u32 {
    u32::from(render::DROP_FLASH)
}

/// Where tile column (or row: the layout is the same along both) `i` begins,
/// in mm; `i = nx` gives where the last one ends. Walls and cells differ in
/// width, so the page draws them from these edges.
#[no_mangle]
pub extern "C" fn tile_edge_mm(i: i32) -> f64 {
    with_app(0.0, |app| {
        let layout = &app.player.game().world().params().layout;
        layout.to_mm(layout.span_xz(i).0)
    })
}

/// A tile pitch in mm: the height between two storeys' floors (eq. 5).
#[no_mangle]
pub extern "C" fn pitch_mm() -> f64 {
    with_app(0.0, |app| {
        f64::from(app.player.game().world().params().layout.pitch_um) / 1000.0
    })
}

/// The marble radius, mm.
#[no_mangle]
pub extern "C" fn marble_radius_mm() -> f64 {
    with_app(0.0, |app| {
        f64::from(app.level().info.spec.radius_um) / 1000.0
    })
}

/// Marbles in the level.
#[no_mangle]
pub extern "C" fn marble_count() -> u32 {
    with_app(0, |app| app.player.game().world().marbles().len() as u32)
}

/// Coordinate `axis` (0 x right, 1 y up, 2 z towards the player) of marble
/// `index`'s centre, mm in the tile frame (0 for no such marble).
#[no_mangle]
pub extern "C" fn marble_mm(index: u32, axis: u32) -> f64 {
    with_app(0.0, |app| {
        marble_coord(app.player.game().world(), index, axis)
    })
}

/// 1 if marble `index` is out of play (fell).
#[no_mangle]
pub extern "C" fn marble_out(index: u32) -> u32 {
    with_app(1, |app| is_out(app.player.game().world(), index) as u32)
}
