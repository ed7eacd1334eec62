//! The AN386's CMSDK APB UARTs, as `embedded-io` byte streams: a receive half and a transmit
//! half, each moved into the hardware task bound to its interrupt.
//!
//! Register map (ARM CMSDK APB UART): DATA, STATE (bit 0 TX buffer full, bit 1 RX buffer full),
//! CTRL (TX/RX enable, TX/RX interrupt enable), INTSTATUS/INTCLEAR, BAUDDIV.

use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, Ordering};

use embedded_io::{ErrorType, Read, ReadReady, Write, WriteReady};
use vcell::VolatileCell;

/// Base addresses: UART0 (the control link), UART1 (the Ping360), UART2 (MAVLink).
const BASES: [usize; 3] = [0x4000_4000, 0x4000_5000, 0x4000_6000];

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INT: u32 = 1 << 2;
const CTRL_RX_INT: u32 = 1 << 3;
const INT_TX: u32 = 1 << 0;
const INT_RX: u32 = 1 << 1;

#[repr(C)]
struct Registers {
    data: VolatileCell<u32>,
    state: VolatileCell<u32>,
    ctrl: VolatileCell<u32>,
    /// INTSTATUS when read, INTCLEAR when written.
    int: VolatileCell<u32>,
    bauddiv: VolatileCell<u32>,
}

/// Which UARTs have been handed out (each at most once, so each register is driven by one
/// owner: see [`registers`]).
static TAKEN: [AtomicBool; 3] = [
    AtomicBool::new(false),
    AtomicBool::new(false),
    AtomicBool::new(false),
];

fn registers(base: usize) -> &'static Registers {
    // # Safety
    // `base` is one of `BASES`: a CMSDK UART's register block, always mapped on this board,
    // 4-byte aligned, and touched only through `VolatileCell`s (volatile loads and stores, no
    // references into the registers escape). Each UART is handed out once (`TAKEN`), split
    // into halves that write disjoint bits: the receive half clears only the RX interrupt,
    // reads DATA and flips CTRL's RX-interrupt bit; the transmit half writes DATA and flips
    // CTRL's TX-interrupt bit. Both halves' tasks run at one priority (they never preempt each
    // other), so their read-modify-writes of CTRL do not interleave.
    #[allow(unsafe_code)]
    unsafe {
        &*(base as *const Registers)
    }
}

/// A UART, before it is split into its two halves.
pub struct Uart {
    base: usize,
}

impl Uart {
    /// UART `n` (0, 1 or 2), enabled at `bauddiv` with its receive interrupt on; `None` if it was
    /// already taken or does not exist.
    pub fn take(n: usize, bauddiv: u32) -> Option<Uart> {
        let base = *BASES.get(n)?;
        if TAKEN.get(n)?.swap(true, Ordering::AcqRel) {
            return None;
        }
        let r = registers(base);
        r.bauddiv.set(bauddiv.max(16));
        r.ctrl.set(CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT);
        Some(Uart { base })
    }

    /// The receive and transmit halves.
    pub fn split(self) -> (UartRx, UartTx) {
        (UartRx { base: self.base }, UartTx { base: self.base })
    }
}

/// A UART's receive half.
pub struct UartRx {
    base: usize,
}

impl UartRx {
    /// Clears the receive interrupt (the handler then drains the buffer).
    pub fn acknowledge(&mut self) {
        registers(self.base).int.set(INT_RX);
    }
}

impl UartRx {
    /// Turns the receive interrupt on or off (off while the link's queue is full: the byte
    /// waits in the UART, and QEMU holds the rest back).
    pub fn listen(&mut self, on: bool) {
        let ctrl = &registers(self.base).ctrl;
        let v = ctrl.get();
        ctrl.set(if on {
            v | CTRL_RX_INT
        } else {
            v & !CTRL_RX_INT
        });
    }
}

impl ErrorType for UartRx {
    type Error = Infallible;
}

impl ReadReady for UartRx {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(registers(self.base).state.get() & STATE_RX_FULL != 0)
    }
}

impl Read for UartRx {
    /// Waits for a byte (callers ask [`ReadReady`] first, so it does not), then takes what the
    /// one-byte buffer holds.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let Some(slot) = buf.first_mut() else {
            return Ok(0);
        };
        let r = registers(self.base);
        while r.state.get() & STATE_RX_FULL == 0 {}
        *slot = r.data.get() as u8;
        Ok(1)
    }
}

/// A UART's transmit half.
pub struct UartTx {
    base: usize,
}

impl UartTx {
    /// Clears the transmit interrupt.
    pub fn acknowledge(&mut self) {
        registers(self.base).int.set(INT_TX);
    }

    /// Turns the transmit interrupt on (bytes remain to send) or off.
    pub fn interrupt_when_ready(&mut self, on: bool) {
        let ctrl = &registers(self.base).ctrl;
        let v = ctrl.get();
        ctrl.set(if on {
            v | CTRL_TX_INT
        } else {
            v & !CTRL_TX_INT
        });
    }
}

impl ErrorType for UartTx {
    type Error = Infallible;
}

impl WriteReady for UartTx {
    fn write_ready(&mut self) -> Result<bool, Infallible> {
        Ok(registers(self.base).state.get() & STATE_TX_FULL == 0)
    }
}

impl Write for UartTx {
    /// Waits for room (callers ask [`WriteReady`] first, so it does not), then sends one byte.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        let Some(&b) = buf.first() else {
            return Ok(0);
        };
        let r = registers(self.base);
        while r.state.get() & STATE_TX_FULL != 0 {}
        r.data.set(u32::from(b));
        Ok(1)
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}
