//! The race's packets on the air: the micro:bit v2's radio, one IEEE 802.15.4
//! frame a packet (the one mode embassy-nrf drives the nRF52833's radio in;
//! the hardware adds and checks the frame's own 2-byte CRC). Each frame is
//! the sender's group, one byte, then the packet: a board drops the frames of
//! other groups before the protocol sees them, so pairs of racers on one
//! channel keep to their own group (chosen with the buttons,
//! `input::race_setup`). A frame that is not a race packet at all (another
//! 802.15.4 network on the channel) fails the packet's checks after this.

use super::packet::MAX_PACKET;

/// The payload of one IEEE 802.15.4 frame (embassy-nrf's
/// `radio::ieee802154::Packet::CAPACITY`): the group byte and a packet.
pub const AIR_FRAME: usize = 125;
const _: () = assert!(MAX_PACKET < AIR_FRAME);

/// Why a frame from the air was dropped before the protocol saw it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AirDrop {
    /// Empty, or longer than a group byte and the longest packet.
    Length,
    /// Another group's.
    OtherGroup,
}

/// `packet` as a frame of `group`, into `out`; `None` if the packet is longer
/// than [`MAX_PACKET`] (no packet the protocol writes is).
pub fn frame<'a>(group: u8, packet: &[u8], out: &'a mut [u8; AIR_FRAME]) -> Option<&'a [u8]> {
    let n = packet.len();
    if n > MAX_PACKET {
        return None;
    }
    out[0] = group;
    out[1..=n].copy_from_slice(packet);
    Some(&out[..=n])
}

/// The packet in `frame`, if it is `group`'s.
pub fn unframe(group: u8, frame: &[u8]) -> Result<&[u8], AirDrop> {
    match frame.split_first() {
        Some((&g, packet)) if packet.len() <= MAX_PACKET => {
            if g == group {
                Ok(packet)
            } else {
                Err(AirDrop::OtherGroup)
            }
        }
        _ => Err(AirDrop::Length),
    }
}

/// What a board's radio did with the frames, for its log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AirCounters {
    /// Frames sent.
    pub sent: u32,
    /// Frames not sent: the channel was busy (clear channel assessment) or
    /// the packet too long. The protocol repeats what they carried.
    pub not_sent: u32,
    /// Frames received with a good radio CRC and handed on.
    pub received: u32,
    /// Frames whose radio CRC failed.
    pub crc: u32,
    /// Frames dropped by [`unframe`]: another group's, or of a wrong length.
    pub other: u32,
    /// Packets dropped because the queue to the race was full.
    pub overflow: u32,
}
