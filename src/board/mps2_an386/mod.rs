//! The emulated ARM MPS2 AN386 board (QEMU `-machine mps2-an386 -cpu cortex-m4`): its CMSDK APB
//! UART0 and its ethernet controller (two ways into the control link: [`eth`]), UART1 (the
//! Ping360: QEMU's second `-serial`) and UART2 (MAVLink: the third), SysTick as the period
//! timer and instruction counter, semihosting for logs and exit.
//!
//! Under `-icount shift=0` QEMU advances the virtual clock by 1 ns per executed instruction, and
//! SysTick counts its 25 MHz reference clock, so one SysTick count is 40 instructions. That makes
//! SysTick both the absolute-schedule period timer and an instruction counter (checked against
//! an exact counter to within 0.1 %). The DWT cycle counter reads 0 on QEMU. Without `-icount`
//! the counts are still a relative measure, not instructions.

mod app;
pub mod device;
pub mod eth;
pub mod uart;

use cortex_m::peripheral::SYST;
use vpf::link::CostUnit;

use super::systick::PeriodTimer;
pub use uart::{UartRx, UartTx};

/// SysTick reference clock, Hz.
pub const SYSTICK_HZ: u32 = 25_000_000;
/// Instructions per SysTick count under `-icount shift=0` (1 ns per instruction, 40 ns a count).
pub const INSTRUCTIONS_PER_TICK: u32 = 40;
/// The unit of [`cost_now`].
pub const COST_UNIT: CostUnit = CostUnit::Instructions;
/// UART baud rate (QEMU ignores it; a real CMSDK UART would use it).
pub const BAUD: u32 = 115_200;

/// What [`init`] hands to the firmware's contexts.
pub struct Parts {
    /// The period timer (SysTick), for the periodic task.
    pub timer: PeriodTimer,
    /// The watchdog, fed by the periodic task.
    pub watchdog: Watchdog,
    /// UART0, the control link: receive half (UART0RX task) and transmit half (UART0TX task).
    pub control: (UartRx, UartTx),
    /// The ethernet controller, the control link's other way in (ETHERNET task); `None` if it
    /// did not come up (the link is then UART0 alone).
    pub ethernet: Option<eth::Ethernet>,
    /// UART1, the Ping360: receive half (UART1RX task) and transmit half (UART1TX task).
    pub sonar: (UartRx, UartTx),
    /// UART2, MAVLink: receive half (UART2RX task) and transmit half (UART2TX task).
    pub mavlink: (UartRx, UartTx),
}

/// Sets up UART0, UART1 and UART2 (receive interrupts on) and the period timer (not yet running).
/// `None` if a UART was already taken (start-up runs once).
pub fn init(syst: SYST) -> Option<Parts> {
    let control = uart::Uart::take(0, SYSTICK_HZ / BAUD)?.split();
    let sonar = uart::Uart::take(1, SYSTICK_HZ / BAUD)?.split();
    let mavlink = uart::Uart::take(2, SYSTICK_HZ / BAUD)?.split();
    Some(Parts {
        timer: PeriodTimer::new(syst, SYSTICK_HZ),
        watchdog: Watchdog,
        control,
        ethernet: eth::Ethernet::take(),
        sonar,
        mavlink,
    })
}

/// Instructions executed so far in this timer interval (see the module notes).
pub fn cost_now() -> u32 {
    let reload = SYST::get_reload();
    let elapsed = reload - SYST::get_current().min(reload);
    elapsed.wrapping_mul(INSTRUCTIONS_PER_TICK)
}

/// Starts transmission of queued bytes on the link the host last spoke on (the transmit
/// interrupt does the rest).
pub fn kick_tx() {
    rtic::pend(if eth::host_here() {
        device::Interrupt::ETHERNET
    } else {
        device::Interrupt::UART0TX
    });
}

/// The background has taken received bytes out of the control link's queue: a frame the
/// ethernet handler left for want of room is taken now.
pub fn received_bytes_taken() {
    if eth::resume_receive() {
        rtic::pend(device::Interrupt::ETHERNET);
    }
}

/// Runs the control link's receive task again (it held a byte back on a full queue).
pub fn resume_control_rx() {
    rtic::pend(device::Interrupt::UART0RX);
}

/// Starts transmission of bytes queued for the Ping360.
pub fn kick_sonar_tx() {
    rtic::pend(device::Interrupt::UART1TX);
}

/// Runs the Ping360's receive task again (it held a byte back on a full queue).
pub fn resume_sonar_rx() {
    rtic::pend(device::Interrupt::UART1RX);
}

/// Starts transmission of bytes queued for the MAVLink line.
pub fn kick_mavlink_tx() {
    rtic::pend(device::Interrupt::UART2TX);
}

/// The emulated board has no watchdog.
pub struct Watchdog;

impl Watchdog {
    /// Nothing to feed.
    pub fn feed(&mut self) {}
    /// Nothing to change in lockstep.
    pub fn enter_lockstep(&mut self) {}
}

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
