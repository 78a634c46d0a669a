//! Best time per level, kept in flash across power-off (feature `records`).
//!
//! A record is the number of game frames ([`FRAME_HZ`](crate::player::FRAME_HZ)
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
//!
//! # Ghosts
//!
//! [`Ghosts`] keeps each level's best run ([`crate::game::ghost`]'s bytes) the
//! same way, in a map of its own beside the records (a full ghosts region
//! never costs a best time); `tests/ghost_flash.rs` cuts the power in a
//! ghost's write, fills the region and offers a ghost longer than a page.

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

mod slot;

pub use slot::Slot;

/// The map both stores keep (one instantiation: [`Slot`]).
type Map<F> = MapStorage<Slot, F, Cache<Uncached, Uncached, Uncached, Slot>>;

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
    /// A level from 128 on was offered: no key holds it ([`Slot::level`]).
    BadLevel,
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
            RecordError::BadLevel => "level index out of range (128 or more)",
        }
    }
}

/// The sequential-storage map of records over the flash `F`, in its region.
pub struct Records<F: NorFlash> {
    map: Map<F>,
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
        let Some(key) = Slot::level(level) else {
            return Ok(None);
        };
        let fetched = self.map.fetch_item::<u32>(&mut self.buffer.0, &key).await;
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
        let Some(key) = Slot::level(level) else {
            return Err(RecordError::BadLevel);
        };
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
        match self.map.store_item(&mut self.buffer.0, &key, &frames).await {
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

/// Where a level's ghost lives in the ghosts' map (with `GHOST_TAG` set:
/// [`Slot::ghost`]): the FNV-1a hash (32 bits) of the level's name (a built-in level's name, or a generated maze's, which
/// holds its arguments). Two names on one key would share a slot; a ghost is
/// used only once its replay wins the level on its own state hash, so the
/// other level's ghost is never shown on the wrong maze, only replaced.
pub const fn ghost_key(name: &str) -> u32 {
    let bytes = name.as_bytes();
    let mut hash: u32 = 0x811C_9DC5;
    let mut i = 0;
    while i < bytes.len() {
        hash ^= bytes[i] as u32;
        hash = hash.wrapping_mul(0x0100_0193);
        i += 1;
    }
    hash
}

/// The longest ghost (bytes) a ghosts' region on flash `F` keeps: an item
/// fills at most one erase page, less the page's two state words, the item's
/// 8-byte header (rounded up to a word) and the 4-byte key.
pub const fn max_ghost_bytes<F: NorFlash>() -> usize {
    let header = 8usize.div_ceil(F::WRITE_SIZE) * F::WRITE_SIZE;
    F::ERASE_SIZE.saturating_sub(2 * F::WRITE_SIZE + header + 4)
}

/// The work buffer [`Ghosts::keep`] needs for a ghost of `len` bytes: its key
/// and bytes, rounded up to the flash's words.
pub const fn ghost_work_bytes<F: NorFlash>(len: usize) -> usize {
    (len + 4).div_ceil(F::WRITE_SIZE) * F::WRITE_SIZE
}

/// Why a ghost could not be read or kept.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GhostStoreError {
    /// Longer than one item of the region may be (`max` bytes): not kept.
    TooLong {
        /// The ghost's length.
        len: usize,
        /// The longest the region keeps.
        max: usize,
    },
    /// The caller's buffer cannot hold the ghost (`needs` bytes).
    Buffer {
        /// The bytes it needs.
        needs: usize,
    },
    /// The region stayed full after the oldest ghosts gave way: not kept.
    Full,
    /// The flash reported an error.
    Flash,
    /// The region was corrupted beyond the crate's repair: it has been erased
    /// (every ghost is lost, the region works again).
    Corrupted,
    /// The region was corrupted and could not even be erased.
    Unrecoverable,
    /// The region held ghosts an older firmware kept under keys of another
    /// form: it has been erased (once; every ghost is lost).
    OlderFormat,
}

impl GhostStoreError {
    /// A short name for logs and the terminal.
    pub const fn as_str(self) -> &'static str {
        match self {
            GhostStoreError::TooLong { .. } => "ghost longer than a flash page: not kept",
            GhostStoreError::Buffer { .. } => "ghost longer than its RAM buffer",
            GhostStoreError::Full => "ghosts region full: not kept",
            GhostStoreError::Flash => "flash error",
            GhostStoreError::Corrupted => "ghosts corrupted: region erased",
            GhostStoreError::Unrecoverable => "ghosts corrupted: erase failed",
            GhostStoreError::OlderFormat => "ghosts of an older firmware: region cleared",
        }
    }
}

/// What [`Ghosts::keep`] did.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Kept {
    /// The bytes written.
    pub bytes: usize,
    /// Other levels' ghosts that gave way for it (the oldest first).
    pub evicted: u8,
}

/// The most ghosts [`Ghosts::keep`] evicts for one ghost before it says
/// [`GhostStoreError::Full`].
const MOST_EVICTIONS: u8 = 16;

/// The best run of each level ([`crate::game::ghost`]'s bytes, as `cargo
/// play` writes them to a file) in sequential-storage's map over the flash
/// `F`, in a region of its own beside the records: one item per level, keyed
/// by [`ghost_key`] of its name.
///
/// Power cuts: as for the records, a ghost is one item with its own CRCs,
/// appended after the one it replaces, so a cut while it is written leaves
/// the old ghost (the new one fails its CRC) or the new one; a ghost read
/// back is also parsed ([`Ghost::parse`](crate::game::ghost::Ghost::parse)),
/// and one that does not parse is no ghost.
///
/// A full region: the ghost of another level that sits oldest in the region
/// (the first met from the oldest page; a page migration moves the live ones
/// forward) gives way — an empty item under its key, which the next
/// migration drops — up to `MOST_EVICTIONS` of them; a ghost longer than one item may be
/// ([`max_ghost_bytes`]) is refused before anything is written.
///
/// Ghosts an older firmware kept under untagged keys (before [`Slot`]: a key
/// whose first byte lacks `GHOST_TAG` reads back as a record's) would sit
/// in the region for ever, never loaded nor evicted: the first load or keep
/// after a power-up looks for them, and finding one erases the region
/// ([`GhostStoreError::OlderFormat`], said once).
pub struct Ghosts<F: NorFlash> {
    map: Map<F>,
    /// The region was looked at for an older firmware's ghosts.
    checked: bool,
}

impl<F: NorFlash> Ghosts<F> {
    /// The ghosts in `region` of `flash` (whole erase pages, at least two).
    /// `None` when the region is not that.
    pub fn new(flash: F, region: core::ops::Range<u32>) -> Option<Self> {
        let config = MapConfig::try_new(region).ok()?;
        Some(Ghosts {
            map: MapStorage::new(flash, config, Cache::new_uncached()),
            checked: false,
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

    /// The ghost of the level `name`, read into `buf`: its bytes, if it has
    /// one that parses. `buf` should hold [`ghost_work_bytes`] of the longest
    /// ghost kept; a stored ghost longer than `buf` is
    /// [`GhostStoreError::Buffer`].
    pub async fn load<'b>(
        &mut self,
        name: &str,
        buf: &'b mut [u8],
    ) -> Result<Option<&'b [u8]>, GhostStoreError> {
        self.check_format(buf).await?;
        let key = Slot::ghost(name);
        let fetched = self.map.fetch_item::<&[u8]>(buf, &key).await;
        match fetched {
            Ok(Some(bytes)) => {
                let whole = crate::game::ghost::Ghost::parse(bytes).is_ok();
                Ok(whole.then_some(bytes))
            }
            Ok(None) => Ok(None),
            Err(Error::BufferTooSmall(needs)) => Err(GhostStoreError::Buffer { needs }),
            Err(e) => Err(self.recover(e).await),
        }
    }

    /// Keeps `ghost` as the level `name`'s, replacing its old one; `work` is
    /// the crate's buffer: at least [`ghost_work_bytes`]`(ghost.len())`, and
    /// to make room in a full region it reads the other ghosts through it
    /// (a buffer for the longest ghost the board keeps). Ghosts evicted for
    /// one that then still does not fit (one the size of a whole page) are
    /// gone.
    pub async fn keep(
        &mut self,
        name: &str,
        ghost: &[u8],
        work: &mut [u8],
    ) -> Result<Kept, GhostStoreError> {
        let max = max_ghost_bytes::<F>();
        if ghost.len() > max {
            return Err(GhostStoreError::TooLong {
                len: ghost.len(),
                max,
            });
        }
        let needs = ghost_work_bytes::<F>(ghost.len());
        if work.len() < needs {
            return Err(GhostStoreError::Buffer { needs });
        }
        match self.check_format(work).await {
            // Said by the load before; the region is empty now.
            Ok(()) | Err(GhostStoreError::OlderFormat) => {}
            Err(e) => return Err(e),
        }
        let key = Slot::ghost(name);
        let mut evicted = 0;
        loop {
            match self.map.store_item(work, &key, &ghost).await {
                Ok(()) => {
                    return Ok(Kept {
                        bytes: ghost.len(),
                        evicted,
                    })
                }
                Err(Error::FullStorage) if evicted < MOST_EVICTIONS => {
                    if !self.evict_oldest(key, work).await? {
                        return Err(GhostStoreError::Full);
                    }
                    evicted += 1;
                }
                Err(Error::FullStorage) => return Err(GhostStoreError::Full),
                Err(Error::ItemTooBig) => {
                    return Err(GhostStoreError::TooLong {
                        len: ghost.len(),
                        max,
                    })
                }
                Err(e) => return Err(self.recover(e).await),
            }
        }
    }

    /// Forgets every ghost.
    pub async fn clear(&mut self) -> Result<(), GhostStoreError> {
        self.map
            .erase_all()
            .await
            .map_err(|_| GhostStoreError::Flash)?;
        self.checked = true;
        Ok(())
    }

    /// Once a power-up: erases the region if it holds an item whose key is
    /// not a ghost's (an older firmware's ghost, see [`Ghosts`]), reading
    /// the items through `work`.
    async fn check_format(&mut self, work: &mut [u8]) -> Result<(), GhostStoreError> {
        if self.checked {
            return Ok(());
        }
        let (_, older) = self.survey(None, work).await?;
        if !older {
            self.checked = true;
            return Ok(());
        }
        match self.map.erase_all().await {
            Ok(()) => {
                self.checked = true;
                Err(GhostStoreError::OlderFormat)
            }
            Err(_) => Err(GhostStoreError::Unrecoverable),
        }
    }

    /// The oldest ghost in the region of a key other than `keep` gets an
    /// empty item (no ghost); `false` when there is none to evict.
    async fn evict_oldest(&mut self, keep: Slot, work: &mut [u8]) -> Result<bool, GhostStoreError> {
        let (oldest, _) = self.survey(Some(keep), work).await?;
        let Some(key) = oldest else {
            return Ok(false);
        };
        match self.map.store_item::<&[u8]>(work, &key, &&[][..]).await {
            Ok(()) => Ok(true),
            Err(Error::FullStorage) => Ok(false),
            Err(e) => Err(self.recover(e).await),
        }
    }

    /// Every item of the region, read through `work`: the key of the ghost
    /// sitting oldest other than `keep`'s, and whether an item's key is not
    /// a ghost's (an older firmware's). One walk for both, so that the
    /// map's walk is linked once.
    async fn survey(
        &mut self,
        keep: Option<Slot>,
        work: &mut [u8],
    ) -> Result<(Option<Slot>, bool), GhostStoreError> {
        // The items come oldest first, a key's newest last: the keys with a
        // ghost, in the order of their newest item (an empty one is a ghost
        // already gone).
        let mut live: heapless::Vec<Slot, 32> = heapless::Vec::new();
        let mut older = false;
        let found = async {
            let mut items = self.map.fetch_all_items(work).await?;
            while let Some((key, value)) = items.next::<&[u8]>(work).await? {
                if !key.is_ghost() {
                    older = true;
                    continue;
                }
                live.retain(|&k| k != key);
                if Some(key) != keep && !value.is_empty() {
                    // More live ghosts than the list holds: the newest wait.
                    let _ = live.push(key);
                }
            }
            Ok::<_, Error<F::Error>>(())
        }
        .await;
        match found {
            Ok(()) => Ok((live.first().copied(), older)),
            Err(Error::BufferTooSmall(needs)) => Err(GhostStoreError::Buffer { needs }),
            Err(e) => Err(self.recover(e).await),
        }
    }

    /// A crate error as ours; a corrupted region is erased first.
    async fn recover(&mut self, e: Error<F::Error>) -> GhostStoreError {
        match e {
            Error::Corrupted { .. } | Error::LogicBug { .. } => match self.map.erase_all().await {
                Ok(()) => GhostStoreError::Corrupted,
                Err(_) => GhostStoreError::Unrecoverable,
            },
            Error::FullStorage => GhostStoreError::Full,
            _ => GhostStoreError::Flash,
        }
    }
}
