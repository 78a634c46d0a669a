//! `cargo play`'s ghosts: the best winning run of each level in a file
//! ([`crate::game::ghost`]'s format), and its replay beside the live game.
//!
//! A level's ghost is `DIR/NAME.ghost` (the level's name, with anything but
//! letters, digits, `-` and `_` as `_`; a generated maze's name holds its seed).
//! A stored ghost is trusted only if its replay ends on its own state hash: a
//! file from an older build, or of a level file edited since, is ignored and
//! replaced by the next win.

use std::format;
use std::fs;
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

use crate::game::ghost::{race_frame, replay, Ghost, GhostWriter, HEADER_BYTES};
use crate::game::level::LevelView;
use crate::game::rules::{Game, GameConfig, Phase};
use crate::game::session::Session;
use crate::input::axes::AccelMg;
use crate::input::tilt::TiltConfig;
use crate::physics::Fx;

/// The file of `level`'s ghost in `dir`.
pub fn path_for(dir: &Path, level: &str) -> PathBuf {
    let name: String = level
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    dir.join(format!("{name}.ghost"))
}

/// A stored ghost whose replay (with `config` and `tilt`) wins `level` and ends
/// on its hash: its readings. `None` for no file, a foreign or broken one, or a
/// stale one.
pub fn load(
    dir: &Path,
    level: LevelView<'static>,
    config: GameConfig,
    tilt: TiltConfig,
) -> Option<Vec<u8>> {
    let bytes = fs::read(path_for(dir, level.info.name)).ok()?;
    let ghost = Ghost::parse(&bytes).ok()?;
    let mut session = Session::<Fx>::new(level, config, tilt).ok()?;
    match replay(&mut session, &ghost) {
        Ok((Phase::Won, true)) => Some(bytes),
        _ => None,
    }
}

/// Follows the attempts at one level, keeps the current one's readings, and
/// writes a win that beats the stored ghost.
#[derive(Debug)]
pub struct GhostKeeper {
    dir: PathBuf,
    level: &'static str,
    tilt: TiltConfig,
    readings: Vec<AccelMg>,
    /// The readings are the attempt's from its first frame (none missed).
    whole: bool,
    /// Frames on the level clock of the stored ghost's win (a run is as fast
    /// as its clock says: looking at the maze first costs nothing).
    best: Option<u32>,
    saved: bool,
}

impl GhostKeeper {
    /// A keeper for `level` (played with `tilt`), whose stored ghost (if any)
    /// took `best` frames on the level clock.
    pub fn new(dir: &Path, level: &'static str, tilt: TiltConfig, best: Option<u32>) -> Self {
        GhostKeeper {
            dir: dir.to_path_buf(),
            level,
            tilt,
            readings: Vec::new(),
            whole: true,
            best,
            saved: false,
        }
    }

    /// Call after every frame the session may have played: a new attempt
    /// starts over, a played frame's reading is kept, and a win that beats the
    /// stored ghost is written — once its replay has ended on the win's state
    /// hash. Returns the file written, if one was.
    pub fn observe(&mut self, session: &Session<'static, Fx>) -> Result<Option<PathBuf>, String> {
        let game = session.game();
        let frames = game.frames() as usize;
        // The same ended attempt, seen again during the pause after it.
        let again = frames == self.readings.len() && game.phase() != Phase::Playing;
        if frames <= self.readings.len() && !again {
            // A new attempt (a restart): kept from its first frame, or not at all.
            self.readings.clear();
            self.saved = false;
            self.whole = frames <= 1;
        }
        if frames == 0 {
            return Ok(None);
        }
        if frames == self.readings.len() + 1 {
            self.readings.push(session.reading());
        } else if frames > self.readings.len() {
            self.whole = false;
        }
        let won = game.phase() == Phase::Won && frames == self.readings.len();
        let clock = game.clock_frames();
        if !won || !self.whole || self.saved || self.best.is_some_and(|b| b <= clock) {
            return Ok(None);
        }
        self.saved = true;
        let mut buf = vec![0u8; HEADER_BYTES + 16 * self.readings.len() + 16];
        let mut w = GhostWriter::new(&mut buf).map_err(|e| e.to_string())?;
        for &r in &self.readings {
            w.push(r).map_err(|e| e.to_string())?;
        }
        let bytes = w
            .finish(session.state_hash(), session.tilt().calibration())
            .map_err(|e| e.to_string())?;
        let ghost = Ghost::parse(bytes).map_err(|e| e.to_string())?;
        let mut check = Session::<Fx>::new(*game.level(), game.config(), self.tilt)
            .map_err(|e| e.to_string())?;
        if replay(&mut check, &ghost) != Ok((Phase::Won, true)) {
            return Err("the run does not replay to its state hash".to_string());
        }
        let path = path_for(&self.dir, self.level);
        fs::create_dir_all(&self.dir)
            .and_then(|()| fs::write(&path, bytes))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        self.best = Some(clock);
        Ok(Some(path))
    }
}

/// A stored ghost played beside the live game, one frame per frame.
#[derive(Debug)]
pub struct GhostRun {
    session: Session<'static, Fx>,
    readings: Vec<AccelMg>,
    /// Its frames before its clock started (see [`race_frame`]).
    idle: u32,
}

impl GhostRun {
    /// The replay of `bytes` (a ghost [`load`] accepted) on `level`.
    pub fn new(
        bytes: &[u8],
        level: LevelView<'static>,
        config: GameConfig,
        tilt: TiltConfig,
    ) -> Option<Self> {
        let ghost = Ghost::parse(bytes).ok()?;
        let readings = ghost.readings().collect::<Result<Vec<_>, _>>().ok()?;
        let mut session = Session::<Fx>::new(level, config, tilt).ok()?;
        session.tilt_mut().set_calibration(ghost.calibration);
        let mut check = session.clone();
        replay(&mut check, &ghost).ok()?;
        let idle = check.game().frames() - check.game().clock_frames();
        Some(GhostRun {
            session,
            readings,
            idle,
        })
    }

    /// Frames of the ghost's run.
    pub fn frames(&self) -> u32 {
        self.readings.len() as u32
    }

    /// Frames of the ghost's run on the level clock: its time.
    pub fn clock(&self) -> u32 {
        self.frames() - self.idle
    }

    /// Plays the ghost as far as it goes beside the live attempt `live`
    /// ([`race_frame`]: from the player's first tilt; from the start again if
    /// the live game restarted), and returns its first marble's tile `(i, k)`
    /// and storey while it is still in the maze.
    pub fn at(&mut self, live: &Game<'_, Fx>) -> Option<(i32, i32, i32)> {
        let frames = race_frame(self.idle, live);
        if frames < self.session.game().frames() {
            self.session.restart();
        }
        while self.session.game().frames() < frames.min(self.frames()) {
            let n = self.session.game().frames() as usize;
            self.session.frame(self.readings[n]);
        }
        let world = self.session.game().world();
        let layout = &world.params().layout;
        let m = world.marbles().first().filter(|m| !m.out)?;
        Some((
            layout.index_xz(m.pos.x),
            layout.index_xz(m.pos.z),
            layout.storey_of(m.pos.y),
        ))
    }
}
