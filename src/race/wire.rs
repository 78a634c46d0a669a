//! The race's packets on a byte stream (a UART joining two boards, QEMU's
//! socket character device): each packet COBS-encoded (the `cobs` crate), so
//! it holds no 0 byte, and a 0 after it. A receiver that joins mid-stream, or
//! loses or garbles bytes, loses at most the packets they belonged to: the
//! next 0 starts afresh, and what a damaged frame decodes to fails the
//! packet's CRC ([`super::packet`]).

use heapless::Vec;

use super::packet::MAX_PACKET;

/// The most bytes a framed packet takes: its COBS encoding and the 0.
pub const MAX_FRAME: usize = cobs::max_encoding_length(MAX_PACKET) + 1;

/// `packet` framed for the stream, into `out`.
pub fn frame<'a>(packet: &[u8], out: &'a mut [u8; MAX_FRAME]) -> &'a [u8] {
    let packet = &packet[..packet.len().min(MAX_PACKET)];
    let n = cobs::encode(packet, &mut out[..MAX_FRAME - 1]);
    out[n] = 0;
    &out[..n + 1]
}

/// What [`Unframer::push`] made of a byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unframed {
    /// Inside a frame, or an empty one (0 after 0).
    Nothing,
    /// A frame longer than any packet's: dropped whole.
    TooLong,
    /// Not COBS: dropped.
    Invalid,
}

/// Cuts a byte stream into packets at its 0 bytes.
#[derive(Clone, Debug)]
pub struct Unframer {
    frame: Vec<u8, MAX_FRAME>,
    packet: [u8; MAX_PACKET],
    too_long: bool,
}

impl Default for Unframer {
    fn default() -> Self {
        Self::new()
    }
}

impl Unframer {
    /// Empty. Bytes before the first 0 may be the end of a frame whose start
    /// this receiver missed: they decode to nothing the packet's checks let
    /// through.
    pub const fn new() -> Self {
        Unframer {
            frame: Vec::new(),
            packet: [0; MAX_PACKET],
            too_long: false,
        }
    }

    /// Takes the next byte of the stream; at the end of a frame, the packet
    /// in it (still to be checked: [`super::RaceLink::receive`]).
    pub fn push(&mut self, byte: u8) -> Result<&[u8], Unframed> {
        if byte != 0 {
            if self.frame.push(byte).is_err() {
                self.too_long = true;
            }
            return Err(Unframed::Nothing);
        }
        let too_long = core::mem::replace(&mut self.too_long, false);
        let frame = core::mem::take(&mut self.frame);
        if too_long {
            return Err(Unframed::TooLong);
        }
        if frame.is_empty() {
            return Err(Unframed::Nothing);
        }
        match cobs::decode(&frame, &mut self.packet) {
            Ok(r) => Ok(&self.packet[..r.frame_size()]),
            Err(_) => Err(Unframed::Invalid),
        }
    }
}
