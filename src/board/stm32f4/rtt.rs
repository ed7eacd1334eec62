//! defmt's global logger over SEGGER RTT: one up channel, named `defmt`, that `probe-rs run`
//! finds by the `_SEGGER_RTT` symbol and decodes with the ELF's defmt table.
//!
//! In place of the `defmt-rtt` crate (and `rtt-target`'s logger), for two reasons:
//! - Both panic when the logger is taken re-entrantly; the compiler cannot prove that
//!   unreachable, so the release image's link-time no-panic check fails. Here a frame begun
//!   while another context is writing one is dropped instead (and counted).
//! - It never blocks: a frame that does not fit is cut short (the host's decoder drops it and
//!   resynchronises at the next frame), whatever mode the host asks for. The firmware logs only
//!   at start-up, on a fault and in the self-test.
//!
//! Everything the host reads is atomics (the ring buffer is `AtomicU8`s, the pointers
//! `AtomicPtr`s), so the control block is `Sync` without `unsafe`; the encoder's state sits in a
//! `critical_section::Mutex`, taken for one `write` at a time by the context that owns the frame.

use core::cell::RefCell;
use core::sync::atomic::{AtomicPtr, AtomicU32, AtomicU8, Ordering};

use cortex_m::peripheral::scb::VectActive;
use cortex_m::peripheral::SCB;
use critical_section::Mutex;

/// The up channel's ring buffer, bytes (one is always left free). It holds the longest line
/// the firmware logs (a self-test report, 246 bytes) with room to spare; the host drains
/// it as it goes. 512 rather than 1 KiB: with 1 KiB the guard's close quarters left
/// 52 bytes of the RAM budget (README, "RAM").
const BUF_SIZE: usize = 512;
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
    name: AtomicPtr<u8>,
    buffer: AtomicPtr<u8>,
    size: u32,
    /// Written by the target only.
    write: AtomicU32,
    /// Written by the host only.
    read: AtomicU32,
    flags: AtomicU32,
}

/// The ring the host reads (in `.bss`).
static BUFFER: [AtomicU8; BUF_SIZE] = [const { AtomicU8::new(0) }; BUF_SIZE];

/// The channel's name, in RAM with the control block (interior mutability puts it in `.data`),
/// so the probe can read the whole control block from RAM.
static NAME: [AtomicU8; 6] = [
    AtomicU8::new(b'd'),
    AtomicU8::new(b'e'),
    AtomicU8::new(b'f'),
    AtomicU8::new(b'm'),
    AtomicU8::new(b't'),
    AtomicU8::new(0),
];

/// The RTT control block; the probe finds it by this symbol.
#[allow(unsafe_code)] // `no_mangle`: the probe looks the block up by its plain name.
#[no_mangle]
static _SEGGER_RTT: Header = Header {
    id: *b"SEGGER RTT\0\0\0\0\0\0",
    max_up_channels: 1,
    max_down_channels: 0,
    up: Channel {
        name: AtomicPtr::new(NAME.as_ptr().cast_mut().cast::<u8>()),
        buffer: AtomicPtr::new(BUFFER.as_ptr().cast_mut().cast::<u8>()),
        size: BUF_SIZE as u32,
        write: AtomicU32::new(0),
        read: AtomicU32::new(0),
        flags: AtomicU32::new(MODE_NON_BLOCKING_TRIM),
    },
};

impl Channel {
    /// Copies as much of `bytes` as fits; drops the rest.
    fn write(&self, bytes: &[u8]) {
        // `% BUF_SIZE`: a host that wrote nonsense into `read` cannot send us out of bounds.
        let mut w = self.write.load(Ordering::Relaxed) as usize % BUF_SIZE;
        let r = self.read.load(Ordering::Acquire) as usize % BUF_SIZE;
        for &b in bytes {
            let next = (w + 1) % BUF_SIZE;
            if next == r {
                break;
            }
            if let Some(slot) = BUFFER.get(w) {
                slot.store(b, Ordering::Relaxed);
            }
            w = next;
        }
        // The host reads no byte before `write` has moved past it.
        self.write.store(w as u32, Ordering::Release);
    }
}

/// No context owns the logger.
const NO_OWNER: u32 = u32::MAX;
/// The context writing a frame: its exception number (0 for thread mode).
static OWNER: AtomicU32 = AtomicU32::new(NO_OWNER);
/// Frames begun by the owner inside its own frame (dropped; only a fault inside a log call
/// could).
static NESTED: AtomicU32 = AtomicU32::new(0);
/// Frames dropped because another context was writing one.
static CONTENDED: AtomicU32 = AtomicU32::new(0);
static ENCODER: Mutex<RefCell<defmt::Encoder>> = Mutex::new(RefCell::new(defmt::Encoder::new()));

/// The running context: 0 in thread mode, else the active exception's number.
fn context() -> u32 {
    match SCB::vect_active() {
        VectActive::ThreadMode => 0,
        VectActive::Exception(e) => (i32::from(e.irqn()) + 16) as u32,
        VectActive::Interrupt { irqn } => u32::from(irqn) + 16,
    }
}

/// Whether the running context owns the frame being written.
fn owned() -> bool {
    OWNER.load(Ordering::Relaxed) == context() && NESTED.load(Ordering::Relaxed) == 0
}

fn emit(bytes: &[u8]) {
    _SEGGER_RTT.up.write(bytes);
}

fn with_encoder(f: impl FnOnce(&mut defmt::Encoder)) {
    critical_section::with(|cs| {
        if let Ok(mut e) = ENCODER.borrow(cs).try_borrow_mut() {
            f(&mut e);
        }
    });
}

#[defmt::global_logger]
struct Logger;

// # Safety
// defmt requires that `acquire` and `release` pair up and that frames do not interleave: a
// frame belongs to the one context that took `OWNER`; `write` and `release` from any other
// context (or from a nested frame of the owner) do nothing, so frames never interleave, and the
// encoder is only touched under a critical section.
#[allow(unsafe_code)]
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        let me = context();
        match OWNER.compare_exchange(NO_OWNER, me, Ordering::Acquire, Ordering::Relaxed) {
            Ok(_) => with_encoder(|e| e.start_frame(emit)),
            Err(owner) if owner == me => {
                NESTED.fetch_add(1, Ordering::Relaxed);
            }
            Err(_) => {
                CONTENDED.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        if OWNER.load(Ordering::Relaxed) != context() {
            return;
        }
        if NESTED.load(Ordering::Relaxed) > 0 {
            NESTED.fetch_sub(1, Ordering::Relaxed);
            return;
        }
        with_encoder(|e| e.end_frame(emit));
        OWNER.store(NO_OWNER, Ordering::Release);
    }

    unsafe fn write(bytes: &[u8]) {
        if owned() {
            with_encoder(|e| e.write(bytes, emit));
        }
    }
}
