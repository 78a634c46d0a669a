//! An interactive terminal as the tilt input: its bytes decoded into tilt
//! and commands by [`KeyTilt`] (QEMU's UART).

use core::future::Future;

use super::input_task::TiltInput;
use crate::input::event::InputEvent;
use crate::input::keys::KeyTilt;

/// Bytes from an interactive terminal (e.g. a UART's receive queue).
pub trait ByteSource {
    /// Waits for the next received byte.
    fn read_byte(&mut self) -> impl Future<Output = u8>;
}

/// [`TiltInput`] from an interactive terminal's bytes, via [`KeyTilt`].
pub struct TerminalInput<S: ByteSource> {
    source: S,
    keys: KeyTilt,
}

impl<S: ByteSource> TerminalInput<S> {
    /// Reads keys from `source`.
    pub const fn new(source: S) -> Self {
        Self {
            source,
            keys: KeyTilt::new(),
        }
    }
}

impl<S: ByteSource> TiltInput for TerminalInput<S> {
    async fn next_event(&mut self) -> InputEvent {
        loop {
            let byte = self.source.read_byte().await;
            if let Some(event) = self.keys.feed(byte) {
                return event;
            }
        }
    }
}
