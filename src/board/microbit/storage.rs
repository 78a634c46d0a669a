//! The micro:bit v2's one flash controller (the NVMC), shared by two tasks:
//! the records task writes the best times in [`RECORDS`], the game task reads
//! and writes the ghosts in [`GHOSTS`] (feature `shared-flash`).
//!
//! Each store gets a [`Region`] of the flash: its own region as offsets from
//! 0, every operation checked against the region's end. So a ghost's write
//! can never reach a best time or the levels region in between, whatever the
//! map does. The flash is blocking (the v2's NVMC): each operation ends within
//! the call, done whole while the region holds the flash's `RefCell`, so two
//! operations never overlap and no borrow is held across an await. (An async
//! mutex held across the flash's await, embassy-embedded-hal's partitions,
//! gave every flash future of both stores drop code: 2.5 KB of the v2's
//! flash.)
//!
//! A blocking operation holds the CPU, and with it the thread executor where
//! the watchdog task runs. A ghost's write in a full region can erase nine
//! pages and write 32 KB (over a second of the NVMC at the datasheet's
//! maxima, [`nvmc_busy_us`]), so after every erase and write a region's task
//! yields, and the other tasks (the watchdog's among them) run.
//! `tests/ghost_flash.rs` checks that the NVMC time between two yields stays
//! under [`LONGEST_STALL_MS`] while ghosts fill the v2's region.

use core::cell::RefCell;
use core::ops::Range;

use embassy_futures::yield_now;
use embedded_storage::nor_flash as blocking;
use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

use super::{GHOSTS, RECORDS, RTC_HZ, WATCHDOG_CHECK_MS, WATCHDOG_TIMEOUT_TICKS};
use crate::board::levels_region;

/// The two stores' regions of one flash.
pub struct Shared<'a, F> {
    /// [`RECORDS`], for `records::Records` over [`local`]`(&RECORDS)`.
    pub records: Region<'a, F>,
    /// [`GHOSTS`], for `records::Ghosts` over [`local`]`(&GHOSTS)`.
    pub ghosts: Region<'a, F>,
}

/// One store's region of a blocking flash `F` shared with the other store,
/// as the async NOR flash the store takes: offsets from the region's start;
/// after each erase and write its task yields to the executor (reads are
/// memory-mapped on the NVMC, and short), so that a blocking flash holds
/// the CPU for one operation at a time, not for a whole store update.
pub struct Region<'a, F> {
    flash: &'a RefCell<F>,
    offset: u32,
    size: u32,
}

/// Why a region's operation failed.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RegionError<E> {
    /// The flash's own error.
    Flash(E),
    /// Past the region's end.
    OutOfBounds,
    /// The flash was in use (an operation within an operation: never on a
    /// single-threaded executor, an error rather than a panic).
    Busy,
}

impl<E: NorFlashError> NorFlashError for RegionError<E> {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            RegionError::Flash(e) => e.kind(),
            RegionError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            RegionError::Busy => NorFlashErrorKind::Other,
        }
    }
}

impl<'a, F> Region<'a, F> {
    /// The region's start in the flash.
    pub fn offset(&self) -> u32 {
        self.offset
    }

    /// The region's length.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// `at..at + len` of the region as flash addresses, if inside it.
    fn span<E>(&self, at: u32, len: usize) -> Result<(u32, u32), RegionError<E>> {
        let len = u32::try_from(len).map_err(|_| RegionError::OutOfBounds)?;
        let end = at.checked_add(len).ok_or(RegionError::OutOfBounds)?;
        if end > self.size {
            return Err(RegionError::OutOfBounds);
        }
        Ok((self.offset + at, self.offset + end))
    }

    /// Runs `operation` on the flash, borrowed for it alone.
    fn with<T, E>(
        &self,
        operation: impl FnOnce(&mut F) -> Result<T, E>,
    ) -> Result<T, RegionError<E>> {
        let mut flash = self.flash.try_borrow_mut().map_err(|_| RegionError::Busy)?;
        operation(&mut flash).map_err(RegionError::Flash)
    }
}

impl<F: blocking::ErrorType> ErrorType for Region<'_, F> {
    type Error = RegionError<F::Error>;
}

impl<F: blocking::ReadNorFlash> ReadNorFlash for Region<'_, F> {
    const READ_SIZE: usize = F::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let (at, _) = self.span(offset, bytes.len())?;
        self.with(|flash| flash.read(at, bytes))
    }

    fn capacity(&self) -> usize {
        self.size as usize
    }
}

impl<F: blocking::NorFlash> NorFlash for Region<'_, F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = to.checked_sub(from).ok_or(RegionError::OutOfBounds)?;
        let (from, to) = self.span(from, len as usize)?;
        let done = self.with(|flash| flash.erase(from, to));
        yield_now().await;
        done
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let (at, _) = self.span(offset, bytes.len())?;
        let done = self.with(|flash| flash.write(at, bytes));
        yield_now().await;
        done
    }
}

/// Whether `region` can be a partition of a flash `F`: not empty, its start
/// and length whole erase pages (and so whole words).
pub const fn fits<F: NorFlash>(region: &Range<u32>) -> bool {
    fits_pages(region, F::READ_SIZE, F::WRITE_SIZE, F::ERASE_SIZE)
}

/// [`fits`] for a flash of these read, write and erase sizes.
const fn fits_pages(region: &Range<u32>, read: usize, write: usize, page: usize) -> bool {
    let (start, end) = (region.start as usize, region.end as usize);
    start < end
        && page > 0
        && read > 0
        && write > 0
        && start % page == 0
        && end % page == 0
        && page.is_multiple_of(read)
        && page.is_multiple_of(write)
}

/// Whether two regions share a byte.
pub const fn overlap(a: &Range<u32>, b: &Range<u32>) -> bool {
    a.start < b.end && b.start < a.end
}

/// The board's regions are apart: the records, the levels region and the
/// ghosts (checked when the crate is built).
const _: () = assert!(
    !overlap(&RECORDS, &GHOSTS)
        && !overlap(&RECORDS, &levels_region::V2)
        && !overlap(&GHOSTS, &levels_region::V2)
);

/// `region` of `flash` as a store's [`Region`]; `None` when it is not whole
/// erase pages of `F` or lies past the flash's end.
pub fn partition<F: blocking::NorFlash>(
    flash: &RefCell<F>,
    region: Range<u32>,
) -> Option<Region<'_, F>> {
    let capacity = flash.try_borrow().ok()?.capacity();
    (fits_pages(&region, F::READ_SIZE, F::WRITE_SIZE, F::ERASE_SIZE)
        && region.end as usize <= capacity)
        .then(|| Region {
            flash,
            offset: region.start,
            size: region.end - region.start,
        })
}

/// The records' and the ghosts' regions of the v2's flash; `None` when a
/// region is not whole pages of `F`.
pub fn share<F: blocking::NorFlash>(flash: &RefCell<F>) -> Option<Shared<'_, F>> {
    Some(Shared {
        records: partition(flash, RECORDS)?,
        ghosts: partition(flash, GHOSTS)?,
    })
}

/// `region`'s partition as its store sees it: all of it, from offset 0.
pub const fn local(region: &Range<u32>) -> Range<u32> {
    0..region.end.saturating_sub(region.start)
}

/// The nRF52833's page erase at most, ms (Product Specification, NVMC
/// electrical specification, t_ERASEPAGE).
pub(crate) const PAGE_ERASE_MS: u64 = 85;

/// The nRF52833's write of one 32-bit word at most, µs (t_WRITE).
pub(crate) const WORD_WRITE_US: u64 = 41;

/// The longest the NVMC may hold the CPU in one go, ms: the watchdog's
/// period less two of its checks (a pet may come a check late, and after
/// the stall every task must beat again before the next one).
pub const LONGEST_STALL_MS: u64 =
    WATCHDOG_TIMEOUT_TICKS as u64 * 1000 / RTC_HZ as u64 - 2 * WATCHDOG_CHECK_MS;

/// The NVMC's time at most for `erases` page erases and `bytes_written`
/// bytes written (whole words), µs. Reads are memory-mapped and not counted.
pub const fn nvmc_busy_us(erases: u64, bytes_written: u64) -> u64 {
    erases * PAGE_ERASE_MS * 1000 + bytes_written.div_ceil(4) * WORD_WRITE_US
}
