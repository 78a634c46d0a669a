//! The micro:bit v2's one flash controller (the NVMC), shared by two tasks:
//! the records task writes the best times in [`RECORDS`], the game task reads
//! and writes the ghosts in [`GHOSTS`] (feature `shared-flash`).
//!
//! Each store gets a partition of the flash (embassy-embedded-hal's
//! [`Partition`]): its own region as offsets from 0, every operation checked
//! against the region's end and the flash locked for it. So a ghost's write
//! can never reach a best time or the levels region in between, whatever the
//! map does, and two operations never overlap: an operation of one task that
//! found the flash busy waits at the lock. On the v2 they never do: the NVMC
//! is blocking (`BlockingAsync`), so each operation ends within the poll that
//! began it and the lock is always free; the mutex is what keeps that true if
//! the flash ever becomes asynchronous.
//!
//! A blocking operation holds the CPU, and with it the thread executor where
//! the watchdog task runs. A ghost's write in a full region can erase nine
//! pages and write 32 KB (over a second of the NVMC at the datasheet's
//! maxima, [`nvmc_busy_us`]), so each store's flash is [`Paced`]: after every
//! erase and write its task yields, and the other tasks (the watchdog's
//! among them) run. `tests/ghost_flash.rs` checks that the NVMC time between
//! two yields stays under [`LONGEST_STALL_MS`] while ghosts fill the v2's
//! region.

use core::ops::Range;

use embassy_embedded_hal::flash::partition::Partition;
use embassy_futures::yield_now;
use embassy_sync::blocking_mutex::raw::RawMutex;
use embassy_sync::mutex::Mutex;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};

use super::{GHOSTS, RECORDS, RTC_HZ, WATCHDOG_CHECK_MS, WATCHDOG_TIMEOUT_TICKS};
use crate::board::levels_region;

/// The two stores' partitions of one flash, each paced.
pub struct Shared<'a, M: RawMutex, F: NorFlash> {
    /// [`RECORDS`], for `records::Records` over [`local`]`(&RECORDS)`.
    pub records: Paced<Partition<'a, M, F>>,
    /// [`GHOSTS`], for `records::Ghosts` over [`local`]`(&GHOSTS)`.
    pub ghosts: Paced<Partition<'a, M, F>>,
}

/// A flash whose task yields to the executor after each erase and write
/// (reads are memory-mapped on the NVMC, and short): a blocking flash then
/// holds the CPU for one operation at a time, not for a whole store update.
/// The yield comes after the partition's lock is released, so the other
/// store's task gets its turn.
pub struct Paced<F>(pub F);

impl<F: ErrorType> ErrorType for Paced<F> {
    type Error = F::Error;
}

impl<F: ReadNorFlash> ReadNorFlash for Paced<F> {
    const READ_SIZE: usize = F::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes).await
    }

    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<F: NorFlash> NorFlash for Paced<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let done = self.0.erase(from, to).await;
        yield_now().await;
        done
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let done = self.0.write(offset, bytes).await;
        yield_now().await;
        done
    }
}

/// Whether `region` can be a partition of a flash `F`: not empty, its start
/// and length whole erase pages (and so whole words).
pub const fn fits<F: NorFlash>(region: &Range<u32>) -> bool {
    let (start, end) = (region.start as usize, region.end as usize);
    let page = F::ERASE_SIZE;
    start < end
        && page > 0
        && F::READ_SIZE > 0
        && F::WRITE_SIZE > 0
        && start % page == 0
        && end % page == 0
        && page % F::READ_SIZE == 0
        && page % F::WRITE_SIZE == 0
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

/// `region` of `flash` as a partition; `None` when it is not whole erase
/// pages (never a panic, which [`Partition::new`] would be).
pub fn partition<'a, M: RawMutex, F: NorFlash>(
    flash: &'a Mutex<M, F>,
    region: Range<u32>,
) -> Option<Partition<'a, M, F>> {
    fits::<F>(&region).then(|| Partition::new(flash, region.start, region.end - region.start))
}

/// The records' and the ghosts' partitions of the v2's flash; `None` when a
/// region is not whole pages of `F`.
pub fn share<M: RawMutex, F: NorFlash>(flash: &Mutex<M, F>) -> Option<Shared<'_, M, F>> {
    Some(Shared {
        records: Paced(partition(flash, RECORDS)?),
        ghosts: Paced(partition(flash, GHOSTS)?),
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
