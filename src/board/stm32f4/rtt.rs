//! defmt's global logger over SEGGER RTT: one up channel, named `defmt`, that `probe-rs run`
//! finds by the `_SEGGER_RTT` symbol and decodes with the ELF's defmt table.
//!
//! In place of the `defmt-rtt` crate, for two reasons:
//! - `defmt-rtt` panics when the logger is taken re-entrantly (a hard fault inside a log call);
//!   the compiler cannot prove that unreachable, so the release image's link-time no-panic
//!   check fails. Here a re-entrant frame is dropped instead.
//! - It never blocks: a frame that does not fit is cut short (the host's decoder drops it and
//!   resynchronises at the next frame), whatever mode the host asks for. Logging holds a
//!   critical section for one frame; waiting in it for the host would stop the UART and the
//!   periodic task. The firmware logs only at start-up, on a fault and in the self-test.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// The up channel's ring buffer, bytes (one is always left free).
const BUF_SIZE: usize = 1024;
/// SEGGER's "non-blocking, trim" mode, as the flags tell the host.
const MODE_NON_BLOCKING_TRIM: u32 = 1;

#[repr(C)]
struct Header {
    id: [u8; 16],
    max_up_channels: u32,
    max_down_channels: u32,
    up: Channel,
}

#[repr(C)]
struct Channel {
    name: *const u8,
    buffer: *mut u8,
    size: u32,
    /// Written by the target only.
    write: AtomicU32,
    /// Written by the host only.
    read: AtomicU32,
    flags: AtomicU32,
}

// SAFETY: the raw pointers are to statics; the target writes `buffer` only under the logger's
// critical section and publishes it through the `write` atomic.
unsafe impl Sync for Header {}

struct Buffer(UnsafeCell<MaybeUninit<[u8; BUF_SIZE]>>);
// SAFETY: written only under the logger's critical section; never read by the target.
unsafe impl Sync for Buffer {}

// Not zeroed at start-up (cortex-m-rt's `.uninit`): the host reads only what `write` covers.
#[link_section = ".uninit.vpf-rtt.BUFFER"]
static BUFFER: Buffer = Buffer(UnsafeCell::new(MaybeUninit::uninit()));

// In RAM with the header, so the probe can read the whole control block from RAM.
#[link_section = ".data.vpf-rtt.NAME"]
static NAME: [u8; 6] = *b"defmt\0";

/// The RTT control block; the probe finds it by this symbol.
#[no_mangle]
static _SEGGER_RTT: Header = Header {
    id: *b"SEGGER RTT\0\0\0\0\0\0",
    max_up_channels: 1,
    max_down_channels: 0,
    up: Channel {
        name: NAME.as_ptr(),
        buffer: BUFFER.0.get().cast::<u8>(),
        size: BUF_SIZE as u32,
        write: AtomicU32::new(0),
        read: AtomicU32::new(0),
        flags: AtomicU32::new(MODE_NON_BLOCKING_TRIM),
    },
};

impl Channel {
    /// Copies as much of `bytes` as fits; drops the rest.
    fn write(&self, mut bytes: &[u8]) {
        while !bytes.is_empty() {
            // `% BUF_SIZE`: a host that wrote nonsense into `read` cannot send us out of bounds.
            let w = self.write.load(Ordering::Relaxed) as usize % BUF_SIZE;
            let r = self.read.load(Ordering::Acquire) as usize % BUF_SIZE;
            // Contiguous free space from `w`: up to `r - 1`, or to the end of the buffer (less
            // one when the reader is at 0, so that a full ring never looks empty).
            let free = if r > w {
                r - w - 1
            } else {
                BUF_SIZE - w - usize::from(r == 0)
            };
            let n = free.min(bytes.len());
            let Some((chunk, rest)) = bytes.split_at_checked(n) else {
                return;
            };
            if chunk.is_empty() {
                return;
            }
            // SAFETY: `w + n <= BUF_SIZE`, so the copy stays in `BUFFER`; the host does not read
            // these bytes until `write` is advanced past them below.
            unsafe {
                core::ptr::copy_nonoverlapping(chunk.as_ptr(), self.buffer.add(w), n);
            }
            self.write
                .store(((w + n) % BUF_SIZE) as u32, Ordering::Release);
            bytes = rest;
        }
    }
}

/// The encoder's state, used only by the context that holds the logger.
struct State {
    encoder: UnsafeCell<defmt::Encoder>,
    restore: UnsafeCell<critical_section::RestoreState>,
}
// SAFETY: accessed only between `acquire` and `release`, under the critical section, by the
// one context that took the logger (`TAKEN`).
unsafe impl Sync for State {}

static STATE: State = State {
    encoder: UnsafeCell::new(defmt::Encoder::new()),
    restore: UnsafeCell::new(critical_section::RestoreState::invalid()),
};
/// A frame is being written.
static TAKEN: AtomicBool = AtomicBool::new(false);
/// Frames begun (and dropped) while another was being written: only an exception that runs
/// with interrupts masked (a hard fault) can do that.
static NESTED: AtomicU32 = AtomicU32::new(0);

fn emit(bytes: &[u8]) {
    _SEGGER_RTT.up.write(bytes);
}

#[defmt::global_logger]
struct Logger;

// SAFETY: `acquire` and `release` pair up (defmt's contract); frames are serialised by the
// critical section, and a nested frame is dropped, never interleaved.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: released in `release`, or at once below for a nested frame.
        let restore = unsafe { critical_section::acquire() };
        if TAKEN.load(Ordering::Relaxed) {
            NESTED.fetch_add(1, Ordering::Relaxed);
            // SAFETY: pairs with the acquire just above (interrupts stay masked: the outer
            // frame's critical section is still held).
            unsafe { critical_section::release(restore) };
            return;
        }
        TAKEN.store(true, Ordering::Relaxed);
        // SAFETY: this context now holds the logger, under the critical section.
        unsafe {
            *STATE.restore.get() = restore;
            (*STATE.encoder.get()).start_frame(emit);
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        if NESTED.load(Ordering::Relaxed) > 0 {
            NESTED.fetch_sub(1, Ordering::Relaxed);
            return;
        }
        if !TAKEN.load(Ordering::Relaxed) {
            return;
        }
        // SAFETY: this context holds the logger (see `acquire`); the critical section is
        // released exactly once, with the state its acquire returned.
        unsafe {
            (*STATE.encoder.get()).end_frame(emit);
            TAKEN.store(false, Ordering::Relaxed);
            critical_section::release(*STATE.restore.get());
        }
    }

    unsafe fn write(bytes: &[u8]) {
        if NESTED.load(Ordering::Relaxed) > 0 || !TAKEN.load(Ordering::Relaxed) {
            return;
        }
        // SAFETY: this context holds the logger (see `acquire`).
        unsafe { (*STATE.encoder.get()).write(bytes, emit) };
    }
}
