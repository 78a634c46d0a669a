//! The one key type of both stores' maps ([`Slot`]): a level's record or a
//! ghost, told apart on flash by the first byte.

use sequential_storage::map::{Key, SerializationError};

use super::ghost_key;

/// The key of an item in either store's map: a level's record or a ghost.
/// One type for both, so that a firmware with both stores links one
/// instantiation of sequential-storage's map (its code is generic over the
/// key: a second one cost the micro:bit v2 3.6 KB of flash).
///
/// On flash a record's key is the level's index, one byte, as it has always
/// been; a ghost's is its 32-bit [`ghost_key`] (little-endian) with
/// `GHOST_TAG` set in its first byte. The first byte tells the two apart:
/// the map hands the key's reader the item's bytes, not their length. So a
/// record's level is below 128 ([`Slot::level`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Slot(
    // The key's four bytes as a number (little-endian): a record's level is
    // below 128 (its three upper bytes zero), a ghost's has GHOST_TAG set in
    // its first byte. One word, so that comparing keys is one compare.
    u32,
);

/// The bit set in the first byte of every ghost's key on flash, clear in a
/// record's.
pub(crate) const GHOST_TAG: u8 = 0x80;

impl Slot {
    /// The record of the level `index`; `None` from 128 on (a byte with
    /// `GHOST_TAG` would read back as a ghost's key).
    pub const fn level(index: u8) -> Option<Slot> {
        if index & GHOST_TAG == 0 {
            Some(Slot(index as u32))
        } else {
            None
        }
    }

    /// The ghost of the level named `name`: [`ghost_key`] with
    /// `GHOST_TAG` set.
    pub const fn ghost(name: &str) -> Slot {
        Slot(ghost_key(name) | GHOST_TAG as u32)
    }

    /// Whether this is a ghost's key.
    pub const fn is_ghost(self) -> bool {
        self.0 & GHOST_TAG as u32 != 0
    }

    /// The key's length on flash.
    const fn len(self) -> usize {
        if self.is_ghost() {
            4
        } else {
            1
        }
    }
}

impl Key for Slot {
    fn serialize_into(&self, buffer: &mut [u8]) -> Result<usize, SerializationError> {
        let len = self.len();
        let out = buffer
            .get_mut(..len)
            .ok_or(SerializationError::BufferTooSmall)?;
        out.copy_from_slice(&self.0.to_le_bytes()[..len]);
        Ok(len)
    }

    fn deserialize_from(buffer: &[u8]) -> Result<(Self, usize), SerializationError> {
        let first = *buffer.first().ok_or(SerializationError::BufferTooSmall)?;
        let slot = if first & GHOST_TAG == 0 {
            Slot(u32::from(first))
        } else {
            let bytes: [u8; 4] = buffer
                .get(..4)
                .and_then(|b| b.try_into().ok())
                .ok_or(SerializationError::BufferTooSmall)?;
            Slot(u32::from_le_bytes(bytes))
        };
        Ok((slot, slot.len()))
    }
}
