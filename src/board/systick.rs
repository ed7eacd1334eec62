//! SysTick as the period timer, on both boards: the hardware reloads it every planner period
//! (or every `1/k` of one, for periods longer than its 24 bits reach), so the schedule is
//! absolute — period `n` starts at `n × T` whatever the tasks cost — and cannot drift.

use core::num::NonZeroU32;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};

/// SysTick, owned by the periodic task once start-up hands it over.
pub struct PeriodTimer {
    syst: SYST,
    hz: u32,
}

impl PeriodTimer {
    /// SysTick counting the core clock at `hz`; stopped until [`PeriodTimer::start`].
    pub fn new(syst: SYST, hz: u32) -> Self {
        PeriodTimer { syst, hz }
    }

    /// Programs an interrupt every `period_ms / k`, `k` the smallest count that fits SysTick's
    /// 24 bits and divides the period's clock counts exactly (one always does for whole
    /// milliseconds at 25 or 180 MHz, so the schedule does not drift). Returns `k`, the
    /// interrupts per period.
    pub fn start(&mut self, period_ms: u32) -> u32 {
        // hz · period / 1000 in 32 bits (a 64-bit division would link compiler_builtins'
        // 1 KiB divider): exact, and saturating only past 4.29e9 ticks (the planner's period
        // is at most 1 s).
        let p = period_ms.max(1);
        let ticks = (self.hz / 1000)
            .saturating_mul(p)
            .saturating_add((self.hz % 1000).saturating_mul(p) / 1000);
        let min_k = ticks.div_ceil(1 << 24).max(1);
        let k = (min_k..min_k.saturating_add(64))
            .filter_map(NonZeroU32::new)
            .find(|&k| ticks % k == 0)
            .map_or(min_k, NonZeroU32::get);
        let reload = (ticks / k.max(1)).clamp(2, 1 << 24) - 1;
        let s = &mut self.syst;
        s.disable_counter();
        s.set_clock_source(SystClkSource::Core);
        s.set_reload(reload);
        s.clear_current();
        s.enable_interrupt();
        s.enable_counter();
        k
    }

    /// Lockstep: the timer stops raising periods; periods then run only when the background
    /// pends SysTick for the host's `Tick`. It counts only while a period runs (the cost
    /// counter, [`PeriodTimer::count`]): a counter left running between periods is a timer
    /// that QEMU's `-icount sleep=off` jumps its virtual clock to whenever the firmware waits
    /// for the host, over and over, keeping a host core busy while the bytes wait for it.
    pub fn enter_lockstep(&mut self) {
        self.syst.disable_interrupt();
        self.syst.disable_counter();
    }

    /// Lockstep: resumes (`true`) or pauses (`false`) the count where it stood, so the cost
    /// counter's differences within a period are as when it runs freely. A count resumed in
    /// the lower half of its interval starts again from the reload value instead (then a
    /// period, far shorter than half an interval, never straddles a reload): the counter loads
    /// it on its next clock, which is waited for, boundedly (under QEMU without `-icount` the
    /// load can come late, and that one period's cost then reads low).
    pub fn count(&mut self, on: bool) {
        let s = &mut self.syst;
        s.disable_counter();
        if !on {
            return;
        }
        if SYST::get_current() < SYST::get_reload() / 2 {
            s.clear_current();
            s.enable_counter();
            let _ = (0..1024).any(|_| SYST::get_current() != 0);
        } else {
            s.enable_counter();
        }
    }

    /// Whether the timer has fired again since the current period began (a missed deadline).
    pub fn overran(&self) -> bool {
        SCB::is_pendst_pending()
    }
}
