//! The ST NUCLEO-F446RE (STM32F446RE, Cortex-M4F): a real board, flashed and logged through
//! its on-board ST-LINK V2-1 with probe-rs.
//!
//! - **Clocks**: 180 MHz from the PLL (the HAL's `rcc`, which also turns on the regulator's
//!   over-drive and sets the flash wait states), fed by the ST-LINK's 8 MHz crystal-accurate MCO
//!   output on OSC_IN (HSE bypass, the board as shipped) when it is there, else by the internal
//!   16 MHz HSI (an ST-LINK part snapped off or unpowered). The HSI is ±1 % at 25 °C but up to
//!   ±4 % over −10…85 °C, which a UART link barely tolerates, so the HSE is preferred; [`init`]
//!   logs which one runs. Should the MCO stop later, the PLL stops and the watchdog resets the
//!   chip, which then starts on the HSI.
//! - **UART**: USART2 at 115 200 baud, 8N1, on PA2 (TX) / PA3 (RX), which the board routes to
//!   the ST-LINK's virtual COM port (solder bridges SB13/SB14 closed, as shipped). The HAL sets
//!   it up; one interrupt (USART2) moves bytes both ways: RX-not-empty fills the receive queue,
//!   TX-empty drains the transmit queue and is on only while bytes remain.
//! - **Ping360 UART**: USART1 at 115 200 baud (the Ping360's default), 8N1, on PA9 (TX) / PA10
//!   (RX): Arduino D8 / D2, morpho CN10 pins 21 / 33. Its interrupt (USART1) moves the sonar
//!   link's bytes the same way; on a full receive queue it turns RX-not-empty off until the
//!   background has taken bytes (the next byte then overruns: lost, as a drop would lose it).
//! - **MAVLink UART**: USART6 at 115 200 baud, 8N1, on PC6 (TX) / PC7 (RX): morpho CN10 pins 4 /
//!   19 (PC7 is also Arduino D9). Its interrupt (USART6) moves the MAVLink line's bytes.
//! - **Period timer**: SysTick on the 180 MHz core clock, as on the emulated board: the
//!   firmware owns the SysTick exception, reads its pending bit for overruns and pends it for
//!   lockstep ticks. A period longer than SysTick's 24 bits reach (93 ms) is split into `k`
//!   equal interrupts, `k` chosen to divide the period's cycles exactly so the schedule does
//!   not drift.
//! - **Cost counter**: the DWT cycle counter (CYCCNT), which counts on real silicon (not on
//!   QEMU): [`COST_UNIT`] is [`CostUnit::Cycles`].
//! - **Watchdog**: the independent watchdog (IWDG, on the ~32 kHz LSI), fed by the periodic
//!   task every period; see [`feed_watchdog`].
//! - **Log**: defmt over RTT (read by `probe-rs run`); no semihosting, which hard-faults without
//!   a debugger. [`exit`] uses semihosting only when a debugger is attached.
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::unreachable,
    clippy::todo,
    clippy::unimplemented
)]

use cortex_m::peripheral::{DCB, DWT, SCB, SYST};
use stm32f4xx_hal::pac::{self, USART1, USART2, USART6};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config as ClockConfig;
use stm32f4xx_hal::serial::{Event, Flag, Instance, Serial};
use vpf::link::CostUnit;

use super::systick::PeriodTimer;

mod app;
mod rtt;

/// Core (and SysTick) clock, Hz.
pub const SYSCLK_HZ: u32 = 180_000_000;
/// The ST-LINK's MCO output, which drives OSC_IN on the board as shipped (UM1724), Hz.
pub const HSE_HZ: u32 = 8_000_000;
/// The internal RC oscillator, Hz.
const HSI_HZ: u32 = 16_000_000;
/// The unit of [`cost_now`].
pub const COST_UNIT: CostUnit = CostUnit::Cycles;
/// UART baud rate (8N1).
pub const BAUD: u32 = 115_200;

/// Watchdog timeout while the timer runs the periods, ms at the LSI's nominal 32 kHz. The LSI
/// may run up to 47 kHz (datasheet), shortening it to 1.36 s: still longer than the longest
/// planner period (1 s, `Params::period_s`), so every valid period feeds it in time, and a hung
/// periodic task resets the board within about 2 s.
pub const WATCHDOG_MS: u32 = 2_000;
/// Watchdog timeout in lockstep, where a period runs only when the host's `Tick` comes: the
/// longest the IWDG can wait (prescaler 256, reload 4095: 32.8 s nominal, 22 s at the fastest
/// LSI), so a host that pauses does not reset the board, and one that is gone does.
pub const WATCHDOG_LOCKSTEP_MS: u32 = 32_768;
const LSI_HZ: u32 = 32_000;

/// What [`init`] hands to the firmware's contexts.
pub struct Parts {
    /// The period timer (SysTick), for the periodic task.
    pub timer: PeriodTimer,
    /// The independent watchdog, fed by the periodic task.
    pub watchdog: Watchdog,
    /// USART2, the control link (both directions in one interrupt).
    pub control: Usart2,
    /// USART1, the Ping360 (both directions in one interrupt).
    pub sonar: Usart1,
    /// USART6, MAVLink (both directions in one interrupt).
    pub mavlink: Usart6,
}

/// Sets up the clocks, USART2 (receive interrupt on), the cycle counter and the watchdog.
/// `None` if the device peripherals were already taken or the UART cannot be configured.
pub fn init(syst: SYST, mut dcb: DCB, mut dwt: DWT) -> Option<Parts> {
    let dp = pac::Peripherals::take()?;
    report_reset_cause(&dp.RCC);
    if DCB::is_debugger_attached() {
        // Keep the bus clocked in WFI so the probe can read the RTT buffer while the idle loop
        // sleeps. The watchdog is deliberately not frozen while the core is halted
        // (DBGMCU_APB1_FZ.DBG_IWDG_STOP stays clear): a core left halted by a breakpoint, or by
        // a semihosting call after the probe went away, is reset rather than stuck.
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
    }

    // The HAL locks the PLL to 180 MHz from the HSI (one constant configuration, so its clock
    // arithmetic and asserts fold away at compile time: a second `freeze` call, for the HSE,
    // kept them, and their panics, in the image); the PLL is then moved onto the HSE if it runs.
    let mut rcc = dp.RCC.freeze(ClockConfig::hsi().sysclk(SYSCLK_HZ.Hz()));
    if pll_onto_hse(&rcc) {
        defmt::info!("vpf-firmware: 180 MHz from the ST-LINK's 8 MHz MCO (HSE bypass)");
    } else {
        defmt::warn!("vpf-firmware: no HSE clock input; 180 MHz from the internal HSI");
    }
    let hclk = rcc.clocks.hclk().raw();

    let gpioa = dp.GPIOA.split(&mut rcc);
    let mut serial = dp
        .USART2
        .serial::<u8>((gpioa.pa2, gpioa.pa3), BAUD.bps(), &mut rcc)
        .ok()?;
    serial.listen(Event::RxNotEmpty);
    let mut sonar = dp
        .USART1
        .serial::<u8>((gpioa.pa9, gpioa.pa10), BAUD.bps(), &mut rcc)
        .ok()?;
    sonar.listen(Event::RxNotEmpty);
    let gpioc = dp.GPIOC.split(&mut rcc);
    let mut mavlink = dp
        .USART6
        .serial::<u8>((gpioc.pc6, gpioc.pc7), BAUD.bps(), &mut rcc)
        .ok()?;
    mavlink.listen(Event::RxNotEmpty);

    dcb.enable_trace();
    dwt.enable_cycle_counter();

    let mut watchdog = Watchdog {
        iwdg: dp.IWDG,
        lockstep: false,
    };
    watchdog.start(WATCHDOG_MS);
    Some(Parts {
        timer: PeriodTimer::new(syst, hclk),
        watchdog,
        control: Usart { serial },
        sonar: Usart { serial: sonar },
        mavlink: Usart { serial: mavlink },
    })
}

/// Moves the PLL, which the HAL locked from the 16 MHz HSI, onto the HSE (the ST-LINK's 8 MHz
/// MCO on OSC_IN, bypass mode) if that clock is there, keeping the PLL's input at the same
/// frequency (M scaled by HSE/HSI): the PLL output, and every clock the HAL computed from it,
/// stay as they were. Returns whether the PLL now runs from the HSE; every wait is bounded, and
/// on a timeout the HSI configuration is put back.
fn pll_onto_hse(rcc: &pac::RCC) -> bool {
    let m_hsi = u32::from(rcc.pllcfgr().read().pllm().bits());
    let m_hse = m_hsi * HSE_HZ / HSI_HZ;
    if m_hse < 2 || m_hse * HSI_HZ != m_hsi * HSE_HZ || !hse_bypass_ready(rcc) {
        return false;
    }
    // Run from the HSI while the PLL is reconfigured (the flash wait states, set for 180 MHz,
    // are safe at any lower clock).
    rcc.cfgr().modify(|_, w| w.sw().hsi());
    let mut on_hse = false;
    if wait_for(|| rcc.cfgr().read().sws().is_hsi()) {
        on_hse = set_pll_source(rcc, true, m_hse);
        if !on_hse {
            // Back to the configuration the HAL locked (and computed its clocks for).
            set_pll_source(rcc, false, m_hsi);
        }
    }
    rcc.cfgr().modify(|_, w| w.sw().pll());
    if !wait_for(|| rcc.cfgr().read().sws().is_pll()) {
        // Not at the clocks the HAL computed (the UART's baud rate, SysTick's period would be
        // wrong): start again rather than run so.
        SCB::sys_reset();
    }
    if !on_hse {
        hse_off(rcc);
    }
    on_hse
}

/// Stops the PLL, sets its source and M, restarts it; whether it locked.
fn set_pll_source(rcc: &pac::RCC, hse: bool, m: u32) -> bool {
    rcc.cr().modify(|_, w| w.pllon().off());
    if !wait_for(|| rcc.cr().read().pllrdy().is_not_ready()) {
        return false;
    }
    rcc.pllcfgr().modify(|_, w| {
        let w = if hse {
            w.pllsrc().hse()
        } else {
            w.pllsrc().hsi()
        };
        // # Safety
        // PLLM takes 2..=63; `m` is in that range (checked by the caller, or read back from the
        // register the HAL configured).
        #[allow(unsafe_code)]
        unsafe {
            w.pllm().bits(m as u8)
        }
    });
    rcc.cr().modify(|_, w| w.pllon().on());
    wait_for(|| rcc.cr().read().pllrdy().is_ready())
}

/// Whether an external clock drives OSC_IN: turns the HSE on in bypass mode and waits for it;
/// turns it off again if it never becomes ready.
fn hse_bypass_ready(rcc: &pac::RCC) -> bool {
    // HSEBYP may be written only while the HSE is off (it is, after reset).
    rcc.cr().modify(|_, w| w.hsebyp().bypassed());
    rcc.cr().modify(|_, w| w.hseon().on());
    if wait_for(|| rcc.cr().read().hserdy().bit_is_set()) {
        return true;
    }
    hse_off(rcc);
    false
}

fn hse_off(rcc: &pac::RCC) {
    rcc.cr().modify(|_, w| w.hseon().off());
    if wait_for(|| rcc.cr().read().hserdy().bit_is_clear()) {
        rcc.cr().modify(|_, w| w.hsebyp().not_bypassed());
    }
}

/// Polls `done` a bounded number of times (about 15 ms at 180 MHz, 200 ms at the 16 MHz HSI: far
/// longer than an external clock, a PLL lock or a clock switch needs); whether it came true.
fn wait_for(mut done: impl FnMut() -> bool) -> bool {
    (0..400_000u32).any(|_| done())
}

/// Logs why the chip last reset (a watchdog reset is worth knowing about), then clears the flags.
fn report_reset_cause(rcc: &pac::RCC) {
    let csr = rcc.csr().read();
    if csr.wdgrstf().bit_is_set() {
        defmt::warn!("vpf-firmware: the last reset was the independent watchdog");
    } else if csr.sftrstf().bit_is_set() {
        defmt::info!("vpf-firmware: the last reset was a software reset (`exit`, or a debugger)");
    }
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
}

/// Core clock cycles since boot (the DWT cycle counter, wrapping every 23.9 s at 180 MHz; the
/// firmware takes wrapping differences).
pub fn cost_now() -> u32 {
    DWT::cycle_count()
}

/// Starts transmission of queued bytes (the USART2 interrupt does the rest).
pub fn kick_tx() {
    rtic::pend(pac::Interrupt::USART2);
}

/// The background has taken received bytes out of the control link's queue (the USART moves
/// one byte at a time and never waits for room: nothing to do).
pub fn received_bytes_taken() {}

/// Runs the control link's interrupt again (it held a byte back on a full queue).
pub fn resume_control_rx() {
    rtic::pend(pac::Interrupt::USART2);
}

/// Starts transmission of bytes queued for the Ping360 (the USART1 interrupt does the rest).
pub fn kick_sonar_tx() {
    rtic::pend(pac::Interrupt::USART1);
}

/// Runs the Ping360's interrupt again (it held a byte back on a full queue).
pub fn resume_sonar_rx() {
    rtic::pend(pac::Interrupt::USART1);
}

/// Starts transmission of bytes queued for the MAVLink line (the USART6 interrupt does the
/// rest).
pub fn kick_mavlink_tx() {
    rtic::pend(pac::Interrupt::USART6);
}

/// The independent watchdog (IWDG, on the ~32 kHz LSI), owned by the periodic task: started at
/// start-up, fed every period, given its longest timeout once lockstep begins.
pub struct Watchdog {
    iwdg: pac::IWDG,
    lockstep: bool,
}

impl Watchdog {
    /// Starts the IWDG (it cannot be stopped again) or changes its timeout, and feeds it.
    fn start(&mut self, timeout_ms: u32) {
        // Smallest prescaler 4 << pr whose 12-bit reload reaches the timeout.
        let counts = u64::from(timeout_ms) * u64::from(LSI_HZ) / 1000;
        let mut pr = 0u8;
        while pr < 6 && counts >> (2 + pr) > 0x1000 {
            pr += 1;
        }
        let reload = (counts >> (2 + pr)).clamp(1, 0x1000) as u16 - 1;
        let w = &self.iwdg;
        // A previous update must finish before the registers take a new value (5 LSI cycles).
        wait_watchdog_update(w);
        // The unlock sequence is broken by any other key; only this owner writes keys.
        w.kr().write(|k| k.key().start());
        w.kr().write(|k| k.key().unlock());
        w.pr().write(|p| p.pr().set(pr));
        w.rlr().write(|r| r.rl().set(reload));
        wait_watchdog_update(w);
        w.kr().write(|k| k.key().feed());
    }

    /// Feeds the watchdog (the periodic task, every period).
    pub fn feed(&mut self) {
        self.iwdg.kr().write(|k| k.key().feed());
    }

    /// Lockstep: the watchdog waits as long as it can for the host's ticks (the first call only;
    /// the periodic task calls this on every lockstep period).
    pub fn enter_lockstep(&mut self) {
        if !self.lockstep {
            self.lockstep = true;
            self.start(WATCHDOG_LOCKSTEP_MS);
        }
    }
}

/// Waits, boundedly, for the IWDG's prescaler and reload updates to finish.
fn wait_watchdog_update(w: &pac::iwdg::RegisterBlock) {
    // 5 LSI cycles at the slowest LSI (17 kHz) are 300 µs, or 54 000 core cycles.
    for _ in 0..100_000u32 {
        if w.sr().read().bits() == 0 {
            return;
        }
    }
}

/// A log line over defmt-RTT (`probe-rs run` prints it), without its line break.
pub fn log(line: &[u8]) {
    let line = line.strip_suffix(b"\n").unwrap_or(line);
    match core::str::from_utf8(line) {
        Ok(s) => defmt::info!("{=str}", s),
        Err(_) => defmt::info!("{=[u8]:a}", line),
    }
}

/// Ends the program. Under a debugger (`probe-rs run`) a semihosting exit carries the status
/// back; without one (semihosting would hard-fault) a failure resets the chip, so a vehicle
/// restarts its guidance rather than hang, and a success parks the core.
pub fn exit(success: bool) -> ! {
    if success {
        defmt::info!("vpf-firmware: exit (success)");
    } else {
        defmt::error!("vpf-firmware: exit (failure)");
    }
    if DCB::is_debugger_attached() {
        use cortex_m_semihosting::debug;
        debug::exit(if success {
            debug::EXIT_SUCCESS
        } else {
            debug::EXIT_FAILURE
        });
    }
    if !success {
        SCB::sys_reset();
    }
    loop {
        cortex_m::asm::wfi();
    }
}

/// A USART as an `embedded-io` byte stream (the HAL implements `Write` only, and blocking):
/// reading takes the received byte, or reports the error flag it cleared; writing sends one byte
/// when the data register is empty.
pub struct Usart<U: Instance> {
    serial: Serial<U>,
}

/// USART2, the control link.
pub type Usart2 = Usart<USART2>;
/// USART1, the Ping360.
pub type Usart1 = Usart<USART1>;
/// USART6, MAVLink.
pub type Usart6 = Usart<USART6>;

/// A byte lost on the line (framing, noise, parity or overrun); the link's CRC catches the
/// damaged frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineError;

impl core::fmt::Display for LineError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("UART line error (overrun, noise, framing or parity)")
    }
}

impl core::error::Error for LineError {}

impl embedded_io::Error for LineError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::InvalidData
    }
}

impl<U: Instance> Usart<U> {
    /// Turns the receive interrupt on or off (off while the link's queue is full).
    pub fn listen(&mut self, on: bool) {
        if on {
            self.serial.listen(Event::RxNotEmpty);
        } else {
            self.serial.unlisten(Event::RxNotEmpty);
        }
    }

    /// Turns the transmit-empty interrupt on (bytes remain to send) or off.
    pub fn interrupt_when_ready(&mut self, on: bool) {
        if on {
            self.serial.listen(Event::TxEmpty);
        } else {
            self.serial.unlisten(Event::TxEmpty);
        }
    }
}

impl<U: Instance> embedded_io::ErrorType for Usart<U> {
    type Error = LineError;
}

impl<U: Instance> embedded_io::ReadReady for Usart<U> {
    /// A byte, or an error flag that the next read clears (an overrun raises the interrupt
    /// too, and only a read of the data register clears it).
    fn read_ready(&mut self) -> Result<bool, LineError> {
        let f = self.serial.flags();
        Ok(f.intersects(
            Flag::RxNotEmpty | Flag::Overrun | Flag::Noise | Flag::FramingError | Flag::ParityError,
        ))
    }
}

impl<U: Instance> embedded_io::Read for Usart<U> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LineError> {
        let Some(slot) = buf.first_mut() else {
            return Ok(0);
        };
        loop {
            match self.serial.read() {
                Ok(b) => {
                    *slot = b;
                    return Ok(1);
                }
                Err(stm32f4xx_hal::nb::Error::Other(_)) => return Err(LineError),
                Err(stm32f4xx_hal::nb::Error::WouldBlock) => {}
            }
        }
    }
}

impl<U: Instance> embedded_io::WriteReady for Usart<U> {
    fn write_ready(&mut self) -> Result<bool, LineError> {
        Ok(self.serial.is_tx_empty())
    }
}

impl<U: Instance> embedded_io::Write for Usart<U> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LineError> {
        let Some(&b) = buf.first() else {
            return Ok(0);
        };
        loop {
            match stm32f4xx_hal::prelude::_embedded_hal_serial_nb_Write::write(&mut self.serial, b)
            {
                Ok(()) => return Ok(1),
                Err(stm32f4xx_hal::nb::Error::Other(_)) => return Err(LineError),
                Err(stm32f4xx_hal::nb::Error::WouldBlock) => {}
            }
        }
    }

    fn flush(&mut self) -> Result<(), LineError> {
        Ok(())
    }
}
