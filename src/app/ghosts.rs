//! The ghost on a board (feature `ghosts`): each level's best run kept in
//! flash ([`Ghosts`]), raced beside the next attempt ([`Racer`]) and drawn
//! dimmer than the marble ([`draw_ghost`]), and each attempt recorded
//! ([`Recorder`]) so that a win that beats the ghost's time replaces it.
//!
//! The game task reads the level's ghost when the level starts, and writes a
//! new one when the level is left (between levels, as the records are
//! written): a stored ghost is raced only if its whole replay wins the level
//! on its own state hash, and a new one is written only if its replay does.

use embedded_storage_async::nor_flash::NorFlash;

#[cfg(feature = "defmt")]
use crate::game::ghost::RecordError;
use crate::game::ghost::{Checking, RaceError, Racer, Recorder};
use crate::game::rules::Phase;
use crate::game::session::Session;
use crate::matrix::Frame;
use crate::physics::Fx;
use crate::records::{max_ghost_bytes, GhostStoreError, Ghosts};
use crate::render::{draw_ghost, Viewport};

/// Frames of a ghost's replay played between two yields to the executor: at
/// QEMU's worst frame (51 840 Cortex-M4 instructions) 64 frames are 52 ms of
/// a 64 MHz CPU, far from the watchdog's second, where a whole run of a
/// 2 KiB ghost (over a thousand frames) might not be.
pub(crate) const REPLAY_STRETCH: u32 = 64;

/// The ghost in `bytes` replayed on `live`'s level, game configuration and
/// tilt path to its end a stretch at a time, the task yielding between
/// stretches: the racer, or why not.
async fn check<'a, 'g, const EVENTS: bool>(
    bytes: &'g [u8],
    live: &Session<'a, Fx>,
) -> Result<Racer<'a, 'g, EVENTS>, RaceError> {
    let game = live.game();
    let mut checking =
        Checking::<EVENTS>::new(bytes, *game.level(), game.config(), live.tilt_config())?;
    while !checking.play(REPLAY_STRETCH) {
        embassy_futures::yield_now().await;
    }
    checking.finish()
}

/// The board's ghosts: the store, and two buffers of `N` bytes — the stored
/// ghost being raced (the store's work buffer between levels) and the live
/// attempt being recorded. `N` is the longest run the board keeps (at most
/// one flash page: [`crate::records::max_ghost_bytes`]).
pub struct GhostKit<F: NorFlash, const N: usize> {
    /// The ghosts in flash.
    pub(crate) store: Ghosts<F>,
    /// Runs after each write (QEMU saves its flash image there).
    pub(crate) written: fn(&mut F),
    stored: [u8; N],
    record: [u8; N],
}

impl<F: NorFlash, const N: usize> GhostKit<F, N> {
    /// The kit over `store`.
    pub const fn new(store: Ghosts<F>, written: fn(&mut F)) -> Self {
        GhostKit {
            store,
            written,
            stored: [0; N],
            record: [0; N],
        }
    }

    /// The level's parts for `live`, a fresh attempt at it: its racer (a
    /// stored ghost, read from flash here, to be raced once its replay on
    /// the same level, game configuration and tilt path reaches its hash:
    /// [`LevelGhost::check`], in place) and a recorder of the attempts. Logs
    /// what it found. By reference: an async fn keeps its arguments while it
    /// runs, and a level is large.
    pub(crate) async fn begin<'k, 'a, const EVENTS: bool>(
        &'k mut self,
        live: &Session<'a, Fx>,
    ) -> LevelGhost<'a, 'k, EVENTS> {
        let name = live.game().level().info.name;
        let GhostKit {
            store,
            stored,
            record,
            ..
        } = self;
        // The stored ghost is read into the front of the buffer; the crate
        // wants room for the key and the word rounding too.
        // The load's future ends with this statement: as the scrutinee of
        // the match it would be kept beside the replay's session.
        let loaded = store.load(name, &mut stored[..]).await;
        let racer = match loaded {
            Ok(Some(bytes)) => {
                let game = live.game();
                let checking =
                    Checking::new(bytes, *game.level(), game.config(), live.tilt_config());
                match checking {
                    Ok(checking) => Some(checking),
                    Err(e) => {
                        #[cfg(feature = "defmt")]
                        defmt::warn!("ghost {=str} not raced: {}", name, e);
                        let _ = e;
                        None
                    }
                }
            }
            Ok(None) => None,
            Err(e) => {
                #[cfg(feature = "defmt")]
                defmt::warn!("ghost {=str}: {=str}", name, e.as_str());
                let _ = e;
                None
            }
        };
        LevelGhost {
            racer,
            recorder: Recorder::new(&mut record[..Self::longest()]).ok(),
            best: None,
        }
    }

    /// The longest ghost the kit records and keeps: its buffer less the
    /// key and the word rounding the store needs, at most a flash page's
    /// item ([`max_ghost_bytes`]).
    pub const fn longest() -> usize {
        let words = N / F::WRITE_SIZE * F::WRITE_SIZE;
        let fits = words.saturating_sub(4);
        let page = max_ghost_bytes::<F>();
        if fits < page {
            fits
        } else {
            page
        }
    }

    /// Writes the run the level's recorder left in its buffer (`len` bytes,
    /// [`LevelGhost::leave`]) as the ghost of `name`; logs the outcome.
    pub(crate) async fn keep_recorded(
        &mut self,
        name: &str,
        len: usize,
    ) -> Result<(), GhostStoreError> {
        let Some(bytes) = self.record.get(..len) else {
            return Err(GhostStoreError::Buffer { needs: len });
        };
        keep(&mut self.store, self.written, name, bytes, &mut self.stored).await
    }
}

/// What the game task asks of a board's ghosts ([`GhostKit`]), so that its
/// flash type and buffer size stay the board's.
// The firmware's executors are single-threaded: no `Send` bound is wanted.
#[allow(async_fn_in_trait)]
pub trait GhostStore {
    /// See `GhostKit::begin`.
    async fn begin<'k, 'a, const EVENTS: bool>(
        &'k mut self,
        live: &Session<'a, Fx>,
    ) -> LevelGhost<'a, 'k, EVENTS>;

    /// See `GhostKit::keep_recorded`.
    async fn keep_recorded(&mut self, name: &str, len: usize) -> Result<(), GhostStoreError>;
}

impl<F: NorFlash, const N: usize> GhostStore for GhostKit<F, N> {
    async fn begin<'k, 'a, const EVENTS: bool>(
        &'k mut self,
        live: &Session<'a, Fx>,
    ) -> LevelGhost<'a, 'k, EVENTS> {
        GhostKit::begin(self, live).await
    }

    async fn keep_recorded(&mut self, name: &str, len: usize) -> Result<(), GhostStoreError> {
        GhostKit::keep_recorded(self, name, len).await
    }
}

/// One level's ghost: the racer and the recorder.
pub struct LevelGhost<'a, 'k, const EVENTS: bool> {
    /// The stored ghost, raced once [`LevelGhost::check`] found it good.
    racer: Option<Checking<'a, 'k, EVENTS>>,
    recorder: Option<Recorder<'k>>,
    /// The raced ghost's time (frames on the level clock).
    best: Option<u32>,
}

impl<'a, 'k, const EVENTS: bool> LevelGhost<'a, 'k, EVENTS> {
    /// Replays the stored ghost on `live`'s level to its end a stretch at a
    /// time, the task yielding between stretches: raced if it wins on its
    /// own state hash, dropped (logged) if not. Call once, before the
    /// attempt's first frame.
    pub(crate) async fn check(&mut self, live: &Session<'_, Fx>) {
        let Some(checking) = &mut self.racer else {
            return;
        };
        while !checking.play(REPLAY_STRETCH) {
            embassy_futures::yield_now().await;
        }
        let name = live.game().level().info.name;
        match checking.verify() {
            Ok(racer) => {
                #[cfg(feature = "defmt")]
                defmt::info!(
                    "ghost {=str}: {=usize} bytes, replays to its hash: racing it ({=u32} frames on the clock)",
                    name,
                    racer.bytes(),
                    racer.clock()
                );
                self.best = Some(racer.clock());
            }
            Err(e) => {
                #[cfg(feature = "defmt")]
                defmt::warn!("ghost {=str} not raced: {}", name, e);
                let _ = (e, name);
                self.racer = None;
            }
        }
    }

    /// The checked racer.
    fn raced(&self) -> Option<&Racer<'a, 'k, EVENTS>> {
        self.racer.as_ref().and_then(Checking::racer)
    }

    /// After each frame of `live` (the attempt at the level): records it and
    /// moves the ghost to where it races.
    pub(crate) fn frame(&mut self, live: &Session<'_, Fx>) {
        if let Some(recorder) = &mut self.recorder {
            recorder.observe(live);
        }
        if let Some(racer) = self.racer.as_mut().and_then(Checking::racer_mut) {
            racer.follow(live.game());
        }
    }

    /// Draws the ghost on `frame` (a picture of `live` through `viewport`)
    /// while the attempt is played.
    pub(crate) fn draw<const W: usize, const H: usize>(
        &self,
        frame: &mut Frame<W, H>,
        live: &Session<'_, Fx>,
        viewport: Viewport,
    ) {
        if let (Some(racer), Phase::Playing) = (self.raced(), live.game().phase()) {
            draw_ghost(frame, live.game(), racer.game(), viewport);
        }
    }

    /// The raced ghost, at the end of its run, on its own state hash (the
    /// board replayed it bit-exactly): its frames and hash. `None`: no ghost,
    /// or not at its end.
    pub(crate) fn raced_to_its_end(&self) -> Option<(u32, u64)> {
        let racer = self.raced()?;
        let (frames, hash) = racer.run();
        (racer.game().frames() == frames && racer.state_hash() == hash).then_some((frames, hash))
    }

    /// The level is left with `live`: a win faster on the clock than the
    /// raced ghost (or the first) is to be kept if its recording replays to
    /// a win on its hash ([`replays`], then [`GhostKit::keep_recorded`],
    /// between levels): the recording. Logs why a win is not kept.
    pub(crate) fn leave(self, live: &Session<'_, Fx>) -> Option<&'k [u8]> {
        let game = live.game();
        let name = game.level().info.name;
        let clock = game.clock_frames();
        if game.phase() != Phase::Won || self.best.is_some_and(|b| b <= clock) {
            return None;
        }
        match self.recorder?.finish(live) {
            Ok(bytes) => Some(bytes),
            Err(e) => {
                #[cfg(feature = "defmt")]
                match e {
                    RecordError::TooLong { bytes } => defmt::warn!(
                        "ghost {=str}: the run is longer than the {=usize}-byte buffer: not kept",
                        name,
                        bytes
                    ),
                    RecordError::Missed => {
                        defmt::warn!("ghost {=str}: frames of the run missed: not kept", name)
                    }
                }
                let _ = (e, name);
                None
            }
        }
    }
}

/// Whether `bytes`, the recording of `live`'s winning attempt
/// (`LevelGhost::leave`), replays to a win on its hash: its length if so
/// (for `GhostKit::keep_recorded`). Logs why not. The replay yields to the
/// executor between stretches.
pub async fn replays<const EVENTS: bool>(bytes: &[u8], live: &Session<'_, Fx>) -> Option<usize> {
    match check::<EVENTS>(bytes, live).await {
        Ok(_) => Some(bytes.len()),
        Err(e) => {
            #[cfg(feature = "defmt")]
            defmt::warn!(
                "ghost {=str}: the run does not replay: not kept ({})",
                live.game().level().info.name,
                e
            );
            let _ = e;
            None
        }
    }
}

/// Writes `bytes` as `name`'s ghost through `work`; logs the outcome.
pub(crate) async fn keep<F: NorFlash>(
    store: &mut Ghosts<F>,
    written: fn(&mut F),
    name: &str,
    bytes: &[u8],
    work: &mut [u8],
) -> Result<(), GhostStoreError> {
    let kept = store.keep(name, bytes, work).await;
    match kept {
        Ok(k) => {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "ghost {=str} kept: {=usize} bytes ({=u8} older ghosts gave way)",
                name,
                k.bytes,
                k.evicted
            );
            let _ = k;
            written(store.flash());
            Ok(())
        }
        Err(e) => {
            #[cfg(feature = "defmt")]
            match e {
                GhostStoreError::TooLong { len, max } => defmt::warn!(
                    "ghost {=str}: {=usize} bytes, longer than a flash page allows ({=usize}): not kept",
                    name,
                    len,
                    max
                ),
                _ => defmt::warn!("ghost {=str}: {=str}", name, e.as_str()),
            }
            Err(e)
        }
    }
}
