//! SysTick as the period timer, on both boards: the hardware reloads it every planner period
//! (or every `1/k` of one, for periods longer than its 24 bits reach), so the schedule is
//! absolute — period `n` starts at `n × T` whatever the tasks cost — and cannot drift.

use core::num::NonZeroU64;

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
        let ticks = u64::from(self.hz) * u64::from(period_ms.max(1)) / 1000;
        let min_k = ticks.div_ceil(1 << 24).max(1);
        let k = (min_k..min_k + 64)
            .filter_map(NonZeroU64::new)
            .find(|&k| ticks % k == 0)
            .map_or(min_k, NonZeroU64::get);
        let reload = (ticks / k.max(1)).clamp(2, 1 << 24) as u32 - 1;
        let s = &mut self.syst;
        s.disable_counter();
        s.set_clock_source(SystClkSource::Core);
        s.set_reload(reload);
        s.clear_current();
        s.enable_interrupt();
        s.enable_counter();
        k as u32
    }

    /// Lockstep: the timer stops raising periods (it keeps counting, for the cost counter);
    /// periods then run only when the background pends SysTick for the host's `Tick`.
    pub fn enter_lockstep(&mut self) {
        self.syst.disable_interrupt();
    }

    /// Whether the timer has fired again since the current period began (a missed deadline).
    pub fn overran(&self) -> bool {
        SCB::is_pendst_pending()
    }
}
