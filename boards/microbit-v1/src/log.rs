//! The defmt global logger, with two sinks picked at run time: semihosting
//! in QEMU (QEMU writes it to its stdout, `defmt-print` decodes it), RTT on a
//! board (`probe-rs run` decodes it).
//!
//! Why not `defmt-semihosting` or `defmt-rtt`: each is a global logger of
//! its own and a program can link only one, while this one ELF runs in
//! both places (`hw::detect_emulation`). Semihosting on a board without a
//! debugger would fault; RTT needs a debugger reading RAM, which QEMU has
//! not. The framing is defmt's own [`defmt::Encoder`]; the sinks are small.
//!
//! The M0 has no atomic read-modify-write: the logger takes a critical
//! section for the whole frame (as `defmt-semihosting` does), so a plain
//! flag is enough to catch re-entry.

use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, Ordering};

use semihosting::io::Write as _;

#[defmt::global_logger]
struct Logger;

/// Set while a frame is being written.
static TAKEN: AtomicBool = AtomicBool::new(false);
static mut RESTORE: critical_section::RestoreState = critical_section::RestoreState::invalid();
static mut ENCODER: defmt::Encoder = defmt::Encoder::new();

/// Semihosting: one frame is gathered here and written with one call (a
/// semihosting call per encoder chunk would multiply QEMU's work).
static mut FRAME: heapless::Vec<u8, 64> = heapless::Vec::new();
static mut STDOUT: Option<semihosting::io::Stdout> = None;

// SAFETY: `acquire` takes a critical section held until `release`, and
// refuses re-entry, so the statics above are only ever used by one frame.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: paired with the release in `release`.
        let restore = unsafe { critical_section::acquire() };
        if TAKEN.load(Ordering::Relaxed) {
            panic!("defmt logger taken reentrantly")
        }
        TAKEN.store(true, Ordering::Relaxed);
        // SAFETY: inside the critical section, not re-entered.
        unsafe {
            RESTORE = restore;
            (*addr_of_mut!(ENCODER)).start_frame(sink);
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        // SAFETY: between acquire and release (defmt's contract).
        unsafe {
            (*addr_of_mut!(ENCODER)).end_frame(sink);
            send();
            TAKEN.store(false, Ordering::Relaxed);
            critical_section::release(RESTORE);
        }
    }

    unsafe fn write(bytes: &[u8]) {
        // SAFETY: between acquire and release.
        unsafe { (*addr_of_mut!(ENCODER)).write(bytes, sink) }
    }
}

/// Where encoded bytes go.
fn sink(bytes: &[u8]) {
    if crate::hw::emulated() {
        for &byte in bytes {
            // SAFETY: only called inside a logger frame (critical section).
            let frame = unsafe { &mut *addr_of_mut!(FRAME) };
            if frame.push(byte).is_err() {
                // SAFETY: as above.
                unsafe { send() };
                let _ = frame.push(byte);
            }
        }
    } else {
        rtt::write(bytes);
    }
}

/// Writes the gathered semihosting bytes.
///
/// # Safety
///
/// Inside a logger frame.
unsafe fn send() {
    // SAFETY: the caller holds the logger.
    let (frame, stdout) = unsafe { (&mut *addr_of_mut!(FRAME), &mut *addr_of_mut!(STDOUT)) };
    if frame.is_empty() {
        return;
    }
    if stdout.is_none() {
        *stdout = semihosting::io::stdout().ok();
    }
    if let Some(out) = stdout {
        let _ = out.write_all(frame);
    }
    frame.clear();
}

/// SEGGER RTT, one up channel named "defmt" (what probe-rs looks for),
/// written the way `defmt-rtt` writes it.
mod rtt {
    use core::ptr::{addr_of, addr_of_mut};
    use core::sync::atomic::{compiler_fence, Ordering};

    /// Room for a few log lines (defmt frames are 5 to 30 bytes): probe-rs
    /// drains it continuously and sets [`BLOCK_IF_FULL`], so a burst waits
    /// instead of being lost. 96 rather than 256 bytes: the RAM went to the
    /// sensor path's three chips and the demo's profile (12 KiB budget).
    const SIZE: usize = 96;
    /// `flags & 3`: block when full (probe-rs sets it while attached).
    const BLOCK_IF_FULL: u32 = 2;

    #[repr(C)]
    struct Channel {
        name: *const u8,
        buffer: *mut u8,
        size: u32,
        write: u32,
        read: u32,
        flags: u32,
    }

    #[repr(C)]
    struct Header {
        id: [u8; 16],
        max_up: u32,
        max_down: u32,
        up: Channel,
    }

    static mut BUFFER: [u8; SIZE] = [0; SIZE];

    /// The control block the debugger finds by this symbol.
    #[unsafe(no_mangle)]
    static mut _SEGGER_RTT: Header = Header {
        id: *b"SEGGER RTT\0\0\0\0\0\0",
        max_up: 1,
        max_down: 0,
        up: Channel {
            name: c"defmt".as_ptr().cast(),
            buffer: addr_of_mut!(BUFFER) as *mut u8,
            size: SIZE as u32,
            write: 0,
            read: 0,
            flags: 0,
        },
    };

    /// Appends `bytes` to the ring: waits for the host while it asks to
    /// block, else keeps what fits.
    pub fn write(mut bytes: &[u8]) {
        // SAFETY: the writer side is ours alone (inside the logger's
        // critical section); the host only moves `read` and `flags`, which
        // are read volatile.
        unsafe {
            let channel = addr_of_mut!(_SEGGER_RTT.up);
            let buffer = addr_of_mut!(BUFFER) as *mut u8;
            while !bytes.is_empty() {
                let read = core::ptr::read_volatile(addr_of!((*channel).read)) as usize;
                let write = core::ptr::read_volatile(addr_of!((*channel).write)) as usize;
                let free = if read > write {
                    read - write - 1
                } else {
                    SIZE - write + read - 1
                };
                let room = free.min(SIZE - write);
                if room == 0 {
                    let flags = core::ptr::read_volatile(addr_of!((*channel).flags));
                    if flags & 3 == BLOCK_IF_FULL {
                        continue;
                    }
                    return;
                }
                let n = room.min(bytes.len());
                core::ptr::copy_nonoverlapping(bytes.as_ptr(), buffer.add(write), n);
                compiler_fence(Ordering::SeqCst);
                let next = (write + n) % SIZE;
                core::ptr::write_volatile(addr_of_mut!((*channel).write), next as u32);
                bytes = &bytes[n..];
            }
        }
    }
}
