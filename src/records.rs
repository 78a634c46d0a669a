//! Best time per level, kept in flash across power-off (feature `records`).
//!
//! A record is the number of game frames ([`FRAME_HZ`](crate::game::player::FRAME_HZ)
//! per second) a level took to win, stored under the level's index with
//! `sequential-storage`'s map, over any `embedded-storage-async` NOR flash: the
//! micro:bit v2's NVMC (wrapped by `BlockingAsync`), QEMU's RAM image saved to a
//! host file, the crate's mock flash in host tests.
//!
//! # Why a power cut cannot leave garbage
//!
//! The map never overwrites: a new record is appended as an item (a header with
//! its own CRC, then the key and value with theirs) after the old one, and a
//! fetch returns the newest item whose CRCs hold. A cut while appending leaves a
//! half-written item that fails its CRC and is skipped, so the old record reads
//! back; a cut while a full page is migrated and erased is repaired at the next
//! access (the crate's page states say which step was under way). What the CRCs
//! cannot catch — a value this game would never write (zero frames, or longer
//! than any level's clock allows) — is treated as no record, not trusted.
//! `tests/records.rs` cuts the power at every byte of every flash operation of a
//! record update, including the page migrations, and reads back after each cut.
//!
//! # When the region cannot be read
//!
//! A region the crate reports as corrupted even after its repair is erased and
//! starts empty ([`RecordError::Corrupted`] says that it happened): a lost best
//! time is a small loss, a game that refuses to start is not. Flash errors are
//! reported, never panicked on; the game goes on without records.
//!
//! # Wear
//!
//! An update appends one item: 16 bytes (8 of header, 1 of key and 4 of value,
//! padded to the flash's 4-byte words) — see `tests/records.rs::wear` for the
//! flash operations per update and the pages erased per update, from which the
//! life figure in docs/testing.md comes.

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};
use sequential_storage::Error;

/// The longest time a record may hold, in frames: an hour at 128 frames/s. A
/// stored value past it (or zero) is garbage, not a record.
pub const MAX_RECORD_FRAMES: u32 = 3600 * 128;

/// Room for one item's key and value (1 + 4 bytes), rounded up to the words of
/// any flash this runs on (up to 8 bytes).
const BUFFER: usize = 16;

/// What a finished level's time did to its record.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Offer {
    /// A new record, stored; `previous` is the one it beat (none: the first).
    New {
        /// The record it replaced, in frames.
        previous: Option<u32>,
    },
    /// Not faster than the record `best` (frames), which stays.
    Kept {
        /// The standing record, in frames.
        best: u32,
    },
}

/// Why the records could not be read or written.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordError {
    /// The flash reported an error (read, write or erase).
    Flash,
    /// The region was corrupted beyond the crate's repair: it has been erased
    /// (every record is lost, the region works again).
    Corrupted,
    /// The region was corrupted and could not even be erased.
    Unrecoverable,
    /// The region is full and cannot take the record (cannot happen with a
    /// region of two pages or more and the 8 keys this game writes).
    Full,
    /// A time of zero frames or over [`MAX_RECORD_FRAMES`] was offered.
    BadTime,
}

impl RecordError {
    /// A short name for logs and the terminal.
    pub const fn as_str(self) -> &'static str {
        match self {
            RecordError::Flash => "flash error",
            RecordError::Corrupted => "records corrupted: region erased",
            RecordError::Unrecoverable => "records corrupted: erase failed",
            RecordError::Full => "records region full",
            RecordError::BadTime => "time out of range",
        }
    }
}

/// The sequential-storage map of records over the flash `F`, in its region.
pub struct Records<F: NorFlash> {
    map: MapStorage<u8, F, Cache<Uncached, Uncached, Uncached, u8>>,
    buffer: Buffer,
}

/// The crate's work buffer, word-aligned (some flash drivers want aligned
/// writes; the mock flash checks it).
#[repr(align(4))]
struct Buffer([u8; BUFFER]);

/// Whether `frames` can be a record at all.
pub const fn plausible(frames: u32) -> bool {
    frames > 0 && frames <= MAX_RECORD_FRAMES
}

/// Whether a win in `frames` beats the record `best` (none: any time does).
pub const fn beats(frames: u32, best: Option<u32>) -> bool {
    match best {
        Some(best) => frames < best,
        None => true,
    }
}

impl<F: NorFlash> Records<F> {
    /// The records in `region` of `flash` (byte offsets of the flash, whole
    /// erase pages, at least two). `None` when the region is not that.
    pub fn new(flash: F, region: core::ops::Range<u32>) -> Option<Self> {
        let config = MapConfig::try_new(region).ok()?;
        Some(Records {
            map: MapStorage::new(flash, config, Cache::new_uncached()),
            buffer: Buffer([0; BUFFER]),
        })
    }

    /// The flash back (tests, and QEMU saving its image).
    pub fn into_flash(self) -> F {
        self.map.destroy().0
    }

    /// The flash (QEMU saves its image after an update).
    pub fn flash(&mut self) -> &mut F {
        self.map.flash()
    }

    /// Level `level`'s record in frames, if it has one.
    pub async fn best(&mut self, level: u8) -> Result<Option<u32>, RecordError> {
        let fetched = self.map.fetch_item::<u32>(&mut self.buffer.0, &level).await;
        match fetched {
            Ok(value) => Ok(value.filter(|&frames| plausible(frames))),
            Err(e) => Err(self.recover(e).await),
        }
    }

    /// A win of `level` in `frames`: stored if it beats the record. A region
    /// found corrupted on the way is erased, and the win becomes its first
    /// record (the other levels' records are gone: read them again).
    pub async fn offer(&mut self, level: u8, frames: u32) -> Result<Offer, RecordError> {
        if !plausible(frames) {
            return Err(RecordError::BadTime);
        }
        let previous = match self.best(level).await {
            Ok(previous) => previous,
            // The region was erased: this win is the first record in it.
            Err(RecordError::Corrupted) => None,
            Err(e) => return Err(e),
        };
        if !beats(frames, previous) {
            // `beats` is false only with a record.
            return Ok(Offer::Kept {
                best: previous.unwrap_or(frames),
            });
        }
        match self
            .map
            .store_item(&mut self.buffer.0, &level, &frames)
            .await
        {
            Ok(()) => Ok(Offer::New { previous }),
            Err(e) => Err(self.recover(e).await),
        }
    }

    /// Forgets every record (the owner asked: A+B held at power-on).
    pub async fn clear(&mut self) -> Result<(), RecordError> {
        self.map.erase_all().await.map_err(|_| RecordError::Flash)
    }

    /// A crate error as ours; a corrupted region is erased first.
    async fn recover(&mut self, e: Error<F::Error>) -> RecordError {
        match e {
            Error::Corrupted { .. } | Error::LogicBug { .. } => match self.map.erase_all().await {
                Ok(()) => RecordError::Corrupted,
                Err(_) => RecordError::Unrecoverable,
            },
            Error::FullStorage => RecordError::Full,
            _ => RecordError::Flash,
        }
    }
}
