//! QEMU's flash for the records: a RAM image with NOR flash rules (feature
//! `records`).
//!
//! `mps2-an386` has no flash controller the firmware could program, so the
//! records' region is this image, with the rules of the micro:bit v2's NVMC —
//! 4 KiB erase pages, 4-byte words, a write can only clear bits, an erase sets
//! a page to `0xFF` — so that `sequential-storage` runs exactly the code path
//! it runs on the v2. The firmware loads the image from a host file at start
//! and saves it after each update (semihosting, `boards/qemu`), so records
//! survive from one `cargo qemu` to the next.
//!
//! Written here because the one RAM flash in the ecosystem's crates,
//! embassy-embedded-hal's `MemFlash`, is compiled only for that crate's tests.

use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// The v2's NVMC page.
pub const PAGE: usize = 4096;
/// The v2's NVMC word.
pub(crate) const WORD: usize = 4;

/// A flash of `N` bytes (whole pages) in RAM.
pub struct RamFlash<const N: usize> {
    image: [u8; N],
}

/// What a [`RamFlash`] refuses, as embedded-storage names it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct RamFlashError(pub NorFlashErrorKind);

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

impl<const N: usize> RamFlash<N> {
    /// An erased flash.
    pub const fn new() -> Self {
        const { assert!(N.is_multiple_of(PAGE) && N > 0, "whole pages") };
        RamFlash { image: [0xFF; N] }
    }

    /// The image (to save it).
    pub fn image(&self) -> &[u8; N] {
        &self.image
    }

    /// The image (to load it).
    pub fn image_mut(&mut self) -> &mut [u8; N] {
        &mut self.image
    }

    fn range(
        offset: u32,
        len: usize,
        align: usize,
    ) -> Result<core::ops::Range<usize>, RamFlashError> {
        let start = offset as usize;
        if !start.is_multiple_of(align) || !len.is_multiple_of(align) {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        match start.checked_add(len) {
            Some(end) if end <= N => Ok(start..end),
            _ => Err(RamFlashError(NorFlashErrorKind::OutOfBounds)),
        }
    }
}

impl<const N: usize> Default for RamFlash<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ErrorType for RamFlash<N> {
    type Error = RamFlashError;
}

impl<const N: usize> ReadNorFlash for RamFlash<N> {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let range = Self::range(offset, bytes.len(), 1)?;
        bytes.copy_from_slice(&self.image[range]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize> NorFlash for RamFlash<N> {
    const WRITE_SIZE: usize = WORD;
    const ERASE_SIZE: usize = PAGE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = (to as usize)
            .checked_sub(from as usize)
            .ok_or(RamFlashError(NorFlashErrorKind::OutOfBounds))?;
        let range = Self::range(from, len, PAGE)?;
        self.image[range].fill(0xFF);
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let range = Self::range(offset, bytes.len(), WORD)?;
        // NOR: programming only clears bits.
        for (cell, &byte) in self.image[range].iter_mut().zip(bytes) {
            *cell &= byte;
        }
        Ok(())
    }
}
