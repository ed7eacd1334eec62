//! The emulated ARM MPS2 AN386 board (QEMU `-machine mps2-an386 -cpu cortex-m4`): its CMSDK APB
//! UART0, SysTick as the period timer, and the instruction counter.
//!
//! Under `-icount shift=0` QEMU advances the virtual clock by 1 ns per executed instruction, and
//! SysTick counts its 25 MHz reference clock, so one SysTick count is 40 instructions. That makes
//! SysTick both the absolute-schedule period timer and an exact-enough instruction counter
//! (checked against an exact counter to within 0.1 %). The DWT cycle counter reads 0 on QEMU.

use core::ptr::{read_volatile, write_volatile};

/// SysTick reference clock of the board, Hz.
pub const SYSTICK_HZ: u32 = 25_000_000;
/// Instructions per SysTick count under `-icount shift=0` (1 ns per instruction, 40 ns a count).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;
/// UART0 receive interrupt number (AN386: UARTRX0 = IRQ 0, UARTTX0 = IRQ 1).
pub const UART0_RX_IRQ: u16 = 0;
/// UART0 transmit interrupt number.
pub const UART0_TX_IRQ: u16 = 1;

const UART0: usize = 0x4000_4000;
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INT: u32 = 1 << 2;
const CTRL_RX_INT: u32 = 1 << 3;
const INT_TX: u32 = 1 << 0;
const INT_RX: u32 = 1 << 1;

/// The CMSDK APB UART0: one byte of buffer each way, an interrupt each way.
pub struct Uart0 {
    _private: (),
}

fn reg(offset: usize) -> *mut u32 {
    (UART0 + offset) as *mut u32
}

impl Uart0 {
    /// Enables the UART at `baud` with the receive interrupt on (transmit interrupt off until
    /// there is something to send).
    ///
    /// # Safety
    /// Call once; the returned handle is the only owner of the UART's registers, except that the
    /// interrupt handlers use [`Uart0::steal`] with the same discipline (RX handler reads, TX
    /// handler writes).
    pub unsafe fn init(baud: u32) -> Self {
        let div = (SYSTICK_HZ / baud.max(1)).max(16);
        write_volatile(reg(BAUDDIV), div);
        write_volatile(reg(CTRL), CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT);
        Uart0 { _private: () }
    }

    /// Another handle to the same UART, for an interrupt handler.
    ///
    /// # Safety
    /// The UART must have been initialised, and the caller must not race another context on the
    /// same register operation (the RX handler only reads, the TX handler only writes).
    pub unsafe fn steal() -> Self {
        Uart0 { _private: () }
    }

    /// The received byte, if one is waiting (clears the receive interrupt).
    pub fn try_read(&mut self) -> Option<u8> {
        // SAFETY: volatile access to this board's UART registers, owned by this handle.
        unsafe {
            write_volatile(reg(INTCLEAR), INT_RX);
            if read_volatile(reg(STATE)) & STATE_RX_FULL != 0 {
                Some(read_volatile(reg(DATA)) as u8)
            } else {
                None
            }
        }
    }

    /// Sends `b` if the transmit buffer has room; `false` if it is full.
    pub fn try_write(&mut self, b: u8) -> bool {
        // SAFETY: as above.
        unsafe {
            write_volatile(reg(INTCLEAR), INT_TX);
            if read_volatile(reg(STATE)) & STATE_TX_FULL != 0 {
                return false;
            }
            write_volatile(reg(DATA), b as u32);
        }
        true
    }

    /// Turns the transmit-ready interrupt on (there is something to send) or off.
    pub fn set_tx_interrupt(&mut self, on: bool) {
        // SAFETY: as above; CTRL is only written from contexts that cannot preempt each other
        // mid-operation (the caller masks or owns the TX side).
        unsafe {
            let ctrl = read_volatile(reg(CTRL));
            let ctrl = if on {
                ctrl | CTRL_TX_INT
            } else {
                ctrl & !CTRL_TX_INT
            };
            write_volatile(reg(CTRL), ctrl);
        }
    }
}

/// SysTick as the period timer and the instruction counter.
pub struct Ticker {
    reload: u32,
}

impl Ticker {
    /// Starts SysTick with an interrupt every `period_ticks` counts of the 25 MHz clock (at most
    /// 2²⁴: 0.67 s; slower rates are made of several interrupts by the caller).
    pub fn start(syst: &mut cortex_m::peripheral::SYST, period_ticks: u32) -> Self {
        use cortex_m::peripheral::syst::SystClkSource;
        let reload = period_ticks.clamp(2, 1 << 24) - 1;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(reload);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        Ticker { reload }
    }

    /// Counts elapsed in the current SysTick period (an up-counter from 0 to the reload value).
    pub fn elapsed(&self) -> u32 {
        self.reload - cortex_m::peripheral::SYST::get_current().min(self.reload)
    }

    /// Counts per SysTick period.
    pub fn period(&self) -> u32 {
        self.reload + 1
    }
}
