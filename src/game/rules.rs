//! The rules: a level's marbles in a [`World`], stepped frame by frame, judged after
//! every frame: a marble's centre inside a goal cell wins, a marble out of play
//! (through a hole, off an open edge) falls, and the level's time limit ends the
//! attempt.
//!
//! # The level clock
//!
//! One rule for every board, so that records compare: the clock starts with the
//! first frame that ends with a marble rolling (faster than `CLOCK_START_SPEED_LOG2` says
//! in the board's plane), i.e. at the first tilt that moves anything. Looking at
//! the maze before touching it costs nothing; neither does sensor noise or a
//! hand that is not quite level, which the rolling resistance holds. A tilt
//! rule (an angle in mg) would leave a gap: a tilt just under it rolls the
//! marble for free. The motion is the physics' own state, identical on every
//! board and stepper, so the rule needs no per-board threshold. The frames
//! before the clock starts still step the physics (the state hashes do not
//! depend on the clock), and an attempt nobody touches for its whole time limit
//! (or 8.5 minutes, if the limit is longer) still ends as time up, so an
//! untouched board does not play one attempt for ever.

use crate::input::tilt::GravityMg;
use crate::physics::dynamics::board_motion::BoardTrack;
use crate::physics::world::{Params, SetupError, Stepping, World};
use crate::physics::{Scalar, Vec3};

use super::level::{Cell, LevelView, MAX_MARBLES};

/// Frame rate, substeps and the stepper: `dt = 2^-(frame_log2 + substeps_log2)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GameConfig {
    /// `log2` of the frame rate (the firmware's physics tick).
    pub frame_log2: u32,
    /// `log2` of the physics steps per frame.
    pub substeps_log2: u32,
    /// Fixed steps, or events (then one step per frame is all it takes: the step
    /// follows the physics, not the clock).
    pub stepping: Stepping,
}

impl GameConfig {
    /// What every board and tool plays, and what the accuracy study recommends
    /// (`docs/accuracy.md`): 128 frames/s, each one event step. The one place the
    /// choice is made: the firmware's `Player` takes [`DEFAULT_EVENTS`], `cargo
    /// sim` and the web page start from it.
    pub const DEFAULT: GameConfig = GameConfig::EVENTS;

    /// 128 frames/s, each one event step (see [`Stepping::Events`]).
    pub const EVENTS: GameConfig = GameConfig {
        frame_log2: 7,
        substeps_log2: 0,
        stepping: Stepping::Events,
    };

    /// 128 frames/s × 8 fixed substeps = 1024 steps/s: the study's baseline
    /// (`cargo sim -- --stepping fixed`); no board ships it.
    pub const FIXED: GameConfig = GameConfig {
        frame_log2: 7,
        substeps_log2: 3,
        stepping: Stepping::Fixed,
    };

    /// [`GameConfig::EVENTS`] if `events`, else [`GameConfig::FIXED`].
    pub const fn stepped_by(events: bool) -> GameConfig {
        if events {
            GameConfig::EVENTS
        } else {
            GameConfig::FIXED
        }
    }

    /// Frames per second.
    pub const fn frame_hz(&self) -> u32 {
        1 << self.frame_log2
    }
}

/// Whether [`GameConfig::DEFAULT`] steps by events: the `EVENTS` constant every
/// board's `Player` is built with.
pub const DEFAULT_EVENTS: bool = matches!(GameConfig::DEFAULT.stepping, Stepping::Events);

impl Default for GameConfig {
    fn default() -> Self {
        GameConfig::DEFAULT
    }
}

/// The speed at which a marble counts as rolling and starts the level clock
/// is `2^-CLOCK_START_SPEED_LOG2` tile pitches per second along x or z (1/64:
/// a fraction of a millimetre per second). A marble the rolling resistance
/// holds is still to the bit (`tests/cli.rs`: a flat board's run ends where it
/// started); a tilt that rolls it passes this within a few frames.
pub(crate) const CLOCK_START_SPEED_LOG2: u32 = 6;

/// Where an attempt stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Still rolling.
    Playing,
    /// A marble reached a goal cell.
    Won,
    /// A marble fell through a hole or off the board.
    Fell,
    /// The time limit ran out.
    TimeUp,
}

impl Phase {
    /// `won`, `fell`, `timeout` or `playing` (tools, logs).
    pub const fn as_str(self) -> &'static str {
        match self {
            Phase::Playing => "playing",
            Phase::Won => "won",
            Phase::Fell => "fell",
            Phase::TimeUp => "timeout",
        }
    }
}

/// One attempt at a level.
#[derive(Clone, Debug)]
pub struct Game<'a, S: Scalar> {
    level: LevelView<'a>,
    config: GameConfig,
    world: World<'a, S, MAX_MARBLES>,
    frames: u32,
    /// Frames played before the clock started: all of them until a marble
    /// rolls (see the module doc), then fixed. A `u16` (an attempt untouched
    /// for `u16::MAX` frames, 8.5 minutes, ends as time up): it fits beside
    /// `phase` where a `u32` would grow every copy of the game by 8 B, which
    /// the micro:bit v1's 12 KiB of RAM does not have (`cargo xtask
    /// check-microbit-v1` measures what is left).
    idle: u16,
    phase: Phase,
    board: BoardTrack<S>,
}

impl<'a, S: Scalar> Game<'a, S> {
    /// A fresh attempt at `level`. Inlined into its callers: built in their
    /// frame, the level's setup (`Player::on`, the micro:bit v1's deepest call)
    /// holds one copy of the world fewer, 1.9 KB of the v1's stack.
    #[inline(always)]
    pub fn new(level: LevelView<'a>, config: GameConfig) -> Result<Self, SetupError> {
        let mut spec = level.info.spec;
        spec.step_log2 = config.frame_log2 + config.substeps_log2;
        spec.stepping = config.stepping;
        let params = Params::<S>::new(spec)?;
        let mut starts = [Vec3::ZERO; MAX_MARBLES];
        let n = level.info.starts().len();
        for (slot, start) in starts.iter_mut().zip(level.info.starts()) {
            let (x, z) = cell_centre(&params, start.i, start.k);
            // On its storey's floor slab, whose top is at y' = storey (eq. 5).
            let floor = if cfg!(feature = "storeys") {
                S::from_int(i32::from(start.storey))
            } else {
                S::ZERO
            };
            *slot = Vec3::new(x, floor + params.radius, z);
        }
        let world = World::with_centres(params, level.tiles, &starts[..n])?;
        Ok(Game {
            level,
            config,
            world,
            frames: 0,
            idle: 0,
            phase: Phase::Playing,
            board: BoardTrack::new(),
        })
    }

    /// Starts the attempt over (same level, same configuration).
    pub fn restart(&mut self) {
        if let Ok(fresh) = Game::new(self.level, self.config) {
            let g = self.world.gravity_mg();
            *self = fresh;
            self.world.set_gravity_mg(g);
        }
    }

    /// The level.
    pub fn level(&self) -> &LevelView<'a> {
        &self.level
    }
    /// The physics world.
    pub fn world(&self) -> &World<'a, S, MAX_MARBLES> {
        &self.world
    }
    /// Mutable physics world (tests and tools).
    pub fn world_mut(&mut self) -> &mut World<'a, S, MAX_MARBLES> {
        &mut self.world
    }
    /// The configuration.
    pub fn config(&self) -> GameConfig {
        self.config
    }
    /// Frames played, the clock's idle ones included (the simulated time).
    pub fn frames(&self) -> u32 {
        self.frames
    }
    /// Frames on the level clock (see the module doc): the attempt's time, the
    /// one a record keeps and a display shows; 0 until a marble rolls.
    pub fn clock_frames(&self) -> u32 {
        self.frames - u32::from(self.idle)
    }
    /// Whether the level clock runs (a marble has rolled in this attempt).
    pub fn clock_started(&self) -> bool {
        u32::from(self.idle) < self.frames
    }
    /// Physics steps taken.
    pub fn steps(&self) -> u64 {
        (self.frames as u64) << self.config.substeps_log2
    }
    /// Where the attempt stands.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Sets the apparent gravity (board frame: flat is [`GravityMg::LEVEL`]), as
    /// the tilt path delivers it; here it leaves the input's type for the
    /// physics' vector. With `board_motion`, the change from the last call also
    /// sets the board's rotation (eq. 4 frames of the tilted board).
    pub fn set_gravity_mg(&mut self, g: GravityMg) {
        let g = g.to_array();
        // World::set_gravity_mg returns at once when the pull is unchanged.
        self.world.set_gravity_mg(g);
        if self.level.info.spec.effects.board_motion {
            self.track_board(g);
        }
    }

    fn track_board(&mut self, g: [i32; 3]) {
        let (ex, ez) = self.world.extent();
        let pivot = Vec3::new(ex.half(), S::ZERO, ez.half());
        let motion = self.board.follow(g, pivot, self.config.substeps_log2);
        self.world.set_board_motion(motion);
    }

    /// Plays one frame (all its substeps) and judges it.
    pub fn frame(&mut self) -> Phase {
        match self.config.stepping {
            Stepping::Events => self.frame_in::<true>(),
            Stepping::Fixed => self.frame_in::<false>(),
        }
    }

    /// [`Game::frame`] with the stepper fixed at compile time ([`World::step_in`]):
    /// `EVENTS` must match the configuration's [`Stepping`].
    pub(crate) fn frame_in<const EVENTS: bool>(&mut self) -> Phase {
        if self.phase != Phase::Playing {
            return self.phase;
        }
        for _ in 0..(1u32 << self.config.substeps_log2) {
            self.world.step_in::<EVENTS>();
        }
        let started = self.clock_started();
        self.frames = self.frames.saturating_add(1);
        if !started && !self.rolling() {
            self.idle = self.idle.saturating_add(1);
        }
        self.phase = self.judge();
        self.phase
    }

    /// A marble in play moves faster than [`CLOCK_START_SPEED_LOG2`] says in the
    /// board's plane (a falling one counts only once it rolls).
    ///
    fn rolling(&self) -> bool {
        let limit = S::from_scaled(1, CLOCK_START_SPEED_LOG2, false);
        self.world
            .marbles()
            .iter()
            .any(|m| !m.out && (m.vel.x.abs() > limit || m.vel.z.abs() > limit))
    }

    fn judge(&self) -> Phase {
        let layout = &self.world.params().layout;
        let marbles = self.world.marbles();
        if marbles.iter().any(|m| m.out) {
            return Phase::Fell;
        }
        let in_goal = marbles.iter().any(|m| {
            let (i, k) = (layout.index_xz(m.pos.x), layout.index_xz(m.pos.z));
            let on_storey = |goal: &Cell| {
                !cfg!(feature = "storeys") || i32::from(goal.storey) == layout.storey_of(m.pos.y)
            };
            self.level
                .info
                .goals()
                .iter()
                .any(|goal| i32::from(goal.i) == i && i32::from(goal.k) == k && on_storey(goal))
        });
        if in_goal {
            return Phase::Won;
        }
        // On the clock, or untouched for the whole limit (idle == frames) or
        // as long as `idle` counts.
        let limit = u32::from(self.level.info.time_limit_s).saturating_mul(self.config.frame_hz());
        if self.clock_frames() >= limit || u32::from(self.idle) >= limit.min(u16::MAX.into()) {
            return Phase::TimeUp;
        }
        Phase::Playing
    }
}

/// The centre of cell `(i, k)` in pitches.
pub fn cell_centre<S: Scalar>(p: &Params<S>, i: u8, k: u8) -> (S, S) {
    let (x0, x1) = p.layout.span_xz(i as i32);
    let (z0, z1) = p.layout.span_xz(k as i32);
    (x0 + (x1 - x0).half(), z0 + (z1 - z0).half())
}
