//! What the game is doing, for status displays: the level, the phase, the
//! clock and the reading, and on a level with storeys where its marbles are
//! (QEMU's terminal draws them; the v1's display reads the phase).

#[cfg(feature = "storey-maps")]
use crate::game::level::MAX_MARBLES;
#[cfg(feature = "storey-maps")]
use crate::game::rules::Game;
use crate::game::rules::Phase;
use crate::input::axes::AccelMg;
#[cfg(feature = "storey-maps")]
use crate::physics::Fx;
#[cfg(feature = "storey-maps")]
use crate::render::tile_point;

#[cfg(doc)]
use super::Player;

/// What the game is doing, for status displays (QEMU's terminal).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Index of the level in the player's level list.
    pub level: u8,
    /// Where the attempt stands.
    pub phase: Phase,
    /// Frames on the level clock in this attempt: the time to show, 0 until a
    /// marble rolls
    /// ([`Game::clock_frames`](crate::game::rules::Game::clock_frames)). Not
    /// the frames played: a status is copied often, and the v1 has no RAM for
    /// both.
    pub frames: u32,
    /// The reading fed to the game last.
    pub reading: AccelMg,
    /// Whether the autopilot is playing.
    pub autopilot: bool,
    /// Whether the game is paused because the sensor is down.
    pub sensor_down: bool,
    /// Whether the sound is off.
    pub muted: bool,
    /// The won level on show set a new record ([`Player::announce_record`]).
    pub new_record: bool,
    /// The level's record in frames, as the records task last read it
    /// (feature `records`; the game task fills it in).
    #[cfg(feature = "records")]
    pub best: Option<u32>,
    /// On a level with storeys, where the marbles in play are, one slot per
    /// marble of the level (`None`: out, or no such marble): the first one in
    /// play is the one the view follows (feature `storeys`: QEMU's terminal
    /// draws every storey of such a level and the marbles on theirs). All
    /// `None` on a one-storey level: nothing shows them there, and working
    /// them out every frame cost the QEMU demo 0.07 points of CPU load.
    #[cfg(feature = "storey-maps")]
    pub marbles: [Option<MarbleSpot>; MAX_MARBLES],
    /// The generated maze on show, by its arguments (`None`: a level the
    /// boards hold, a built-in one): QEMU's terminal makes it again to draw
    /// its storeys (feature `storey-maps`; the game task fills it in, the
    /// player does not know where its level came from).
    #[cfg(feature = "storey-maps")]
    pub maze: Option<crate::game::endless::MazeArgs>,
}

/// Where a marble is, for status displays: the tile holding its centre and
/// its storey (0 the lowest). Whole tiles, because that is all a storey map
/// draws: a marble moving within its tile leaves the status as it was, and
/// the display has nothing to redraw.
#[cfg(feature = "storey-maps")]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MarbleSpot {
    /// Tile column `i`.
    pub i: i16,
    /// Tile row `k`.
    pub k: i16,
    /// The storey whose wall layer or floor slab holds the marble's centre.
    pub storey: u8,
}

#[cfg(feature = "storey-maps")]
impl MarbleSpot {
    /// The tile, `(i, k)`.
    pub const fn tile(&self) -> (i32, i32) {
        (self.i as i32, self.k as i32)
    }
}

/// [`Status::marbles`] of `game`'s world (none on a one-storey level).
#[cfg(feature = "storey-maps")]
pub(super) fn marble_spots(game: &Game<'_, Fx>) -> [Option<MarbleSpot>; MAX_MARBLES] {
    let mut spots = [None; MAX_MARBLES];
    if game.level().info.storeys < 2 {
        return spots;
    }
    let world = game.world();
    let layout = &world.params().layout;
    for (spot, m) in spots.iter_mut().zip(world.marbles()) {
        if m.out {
            continue;
        }
        let (i, k) = tile_point(layout, m.pos.x, m.pos.z).tile();
        let narrow = |a: i32| a.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
        *spot = Some(MarbleSpot {
            i: narrow(i),
            k: narrow(k),
            storey: layout.storey_of(m.pos.y).clamp(0, i32::from(u8::MAX)) as u8,
        });
    }
    spots
}

impl Status {
    /// Before the first frame.
    pub const START: Status = Status {
        level: 0,
        phase: Phase::Playing,
        frames: 0,
        reading: AccelMg::LEVEL,
        autopilot: false,
        sensor_down: false,
        muted: false,
        new_record: false,
        #[cfg(feature = "records")]
        best: None,
        #[cfg(feature = "storey-maps")]
        marbles: [None; MAX_MARBLES],
        #[cfg(feature = "storey-maps")]
        maze: None,
    };
}
