//! The emulated ARM MPS2 AN386 board (QEMU `-machine mps2-an386 -cpu cortex-m4`): its CMSDK APB
//! UART0, SysTick as the period timer and instruction counter, semihosting for logs and exit.
//!
//! Under `-icount shift=0` QEMU advances the virtual clock by 1 ns per executed instruction, and
//! SysTick counts its 25 MHz reference clock, so one SysTick count is 40 instructions. That makes
//! SysTick both the absolute-schedule period timer and an instruction counter (checked against
//! an exact counter to within 0.1 %). The DWT cycle counter reads 0 on QEMU. Without `-icount`
//! the counts are still a relative measure, not instructions.

use core::ptr::{read_volatile, write_volatile};

use cortex_m::peripheral::{NVIC, SCB, SYST};
use vpf::link::CostUnit;

/// SysTick reference clock, Hz.
pub const SYSTICK_HZ: u32 = 25_000_000;
/// Instructions per SysTick count under `-icount shift=0` (1 ns per instruction, 40 ns a count).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;
/// The unit of [`cost_now`].
pub const COST_UNIT: CostUnit = CostUnit::Instructions;
/// UART baud rate (QEMU ignores it; a real CMSDK UART would use it).
pub const BAUD: u32 = 115_200;

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

/// AN386 interrupt numbers: UARTRX0 = 0, UARTTX0 = 1.
#[derive(Clone, Copy)]
enum Irq {
    Uart0Rx = 0,
    Uart0Tx = 1,
}

// SAFETY: the numbers are the AN386's, below its 32 external interrupts.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self as u16
    }
}

fn uart(offset: usize) -> *mut u32 {
    (UART0 + offset) as *mut u32
}

/// Sets up UART0 (receive interrupt on) and the interrupt priorities.
pub fn init(mut cp: cortex_m::Peripherals) {
    // SAFETY: volatile writes to this board's UART0 registers, before any interrupt is enabled.
    unsafe {
        write_volatile(uart(BAUDDIV), (SYSTICK_HZ / BAUD).max(16));
        write_volatile(uart(CTRL), CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT);
    }
    // Priorities (lower is more urgent): the byte movers above the periodic task, the periodic
    // task above thread mode. Their bodies are O(1) per byte (module docs of `firmware`).
    // SAFETY: priorities are set once, before the interrupts are unmasked.
    unsafe {
        cp.NVIC.set_priority(Irq::Uart0Rx, 0x00);
        cp.NVIC.set_priority(Irq::Uart0Tx, 0x00);
        cp.SCB
            .set_priority(cortex_m::peripheral::scb::SystemHandler::SysTick, 0x40);
        NVIC::unmask(Irq::Uart0Rx);
        NVIC::unmask(Irq::Uart0Tx);
    }
}

// SysTick control bits (ARMv7-M SYST_CSR).
const CSR_ENABLE: u32 = 1 << 0;
const CSR_TICKINT: u32 = 1 << 1;
const CSR_CLKSOURCE: u32 = 1 << 2;

fn syst() -> &'static cortex_m::peripheral::syst::RegisterBlock {
    // SAFETY: SysTick's register block is always mapped; it is written only by `start_timer`
    // and `enter_lockstep`, each from a context that cannot race the other (start-up / SysTick,
    // and thread mode only once lockstep begins, after which SysTick runs only when pended).
    unsafe { &*SYST::PTR }
}

/// Programs SysTick for a planner period of `period_ms`: interrupts every `period / k`, with `k`
/// the smallest divisor that fits SysTick's 24 bits. Returns `k`, the interrupts per period.
pub fn start_timer(period_ms: u32) -> u32 {
    let ticks = u64::from(SYSTICK_HZ) * u64::from(period_ms.max(1)) / 1000;
    let k = ticks.div_ceil(1 << 24).max(1);
    let reload = (ticks / k).clamp(2, 1 << 24) as u32 - 1;
    let r = syst();
    // SAFETY: plain writes to SysTick's reload, current-value and control registers.
    unsafe {
        r.csr.write(0);
        r.rvr.write(reload);
        r.cvr.write(0);
        r.csr.write(CSR_ENABLE | CSR_TICKINT | CSR_CLKSOURCE);
    }
    k as u32
}

/// Lockstep: the timer stops raising periods (it keeps counting, for the cost counter).
pub fn enter_lockstep() {
    let r = syst();
    // SAFETY: as above; clears only the interrupt enable.
    unsafe { r.csr.modify(|v| v & !CSR_TICKINT) };
}

/// Instructions executed so far in this timer interval (see the module notes).
pub fn cost_now() -> u32 {
    let reload = SYST::get_reload();
    let elapsed = reload - SYST::get_current().min(reload);
    elapsed.wrapping_mul(INSTRUCTIONS_PER_TICK)
}

/// Whether the timer has fired again since the current period began.
pub fn timer_pending() -> bool {
    SCB::is_pendst_pending()
}

/// Starts transmission of queued bytes (the transmit interrupt does the rest).
pub fn kick_tx() {
    NVIC::pend(Irq::Uart0Tx);
}

/// The emulated board has no watchdog.
pub fn feed_watchdog() {}

/// A log line on the host's console (semihosting; QEMU prints it on its stdout).
pub fn log(line: &[u8]) {
    if let Ok(mut out) = cortex_m_semihosting::hio::hstdout() {
        let _ = out.write_all(line);
    }
}

/// Ends the program (semihosting exit, which QEMU turns into its exit status).
pub fn exit(success: bool) -> ! {
    use cortex_m_semihosting::debug;
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

/// UART0 receive: move every waiting byte into the receive queue.
#[allow(non_snake_case)]
#[no_mangle]
extern "C" fn UART0RX() {
    static mut RX: Option<crate::firmware::RxProducer> = None;
    // SAFETY: only this handler touches `RX`, and it cannot preempt itself.
    #[allow(static_mut_refs)]
    let rx = unsafe { &mut RX };
    if rx.is_none() {
        *rx = crate::firmware::rx_producer();
    }
    // SAFETY: volatile reads of UART0; only this handler reads DATA.
    unsafe {
        write_volatile(uart(INTCLEAR), INT_RX);
        while read_volatile(uart(STATE)) & STATE_RX_FULL != 0 {
            let b = read_volatile(uart(DATA)) as u8;
            if let Some(p) = rx.as_mut() {
                crate::firmware::on_rx_byte(p, b);
            }
        }
    }
}

/// UART0 transmit: send queued bytes while the UART takes them; keep the transmit interrupt on
/// only while bytes remain.
#[allow(non_snake_case)]
#[no_mangle]
extern "C" fn UART0TX() {
    static mut TX: Option<crate::firmware::TxConsumer> = None;
    // SAFETY: only this handler touches `TX`, and it cannot preempt itself.
    #[allow(static_mut_refs)]
    let tx = unsafe { &mut TX };
    if tx.is_none() {
        *tx = crate::firmware::tx_consumer();
    }
    let Some(c) = tx.as_mut() else { return };
    // SAFETY: volatile access to UART0; only this handler writes DATA and the TX bits of CTRL.
    unsafe {
        write_volatile(uart(INTCLEAR), INT_TX);
        while read_volatile(uart(STATE)) & STATE_TX_FULL == 0 {
            match c.dequeue() {
                Some(b) => write_volatile(uart(DATA), u32::from(b)),
                None => break,
            }
        }
        let ctrl = read_volatile(uart(CTRL));
        let ctrl = if c.ready() {
            ctrl | CTRL_TX_INT
        } else {
            ctrl & !CTRL_TX_INT
        };
        write_volatile(uart(CTRL), ctrl);
    }
}

/// The device interrupt vector: AN386 external interrupts 0 and 1 (the rest unused).
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [unsafe extern "C" fn(); 2] = [UART0RX, UART0TX];
