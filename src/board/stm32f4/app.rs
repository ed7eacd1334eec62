//! The firmware's contexts on the NUCLEO-F446RE, declared as an RTIC application with the
//! STM32F446's PAC as the device. The same contexts as on the emulated board
//! (`board::mps2_an386::app`, which says more); here one interrupt per USART moves its link's
//! bytes both ways: USART2 the control link's, USART1 the Ping360's, USART6 MAVLink's.

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = false)]
mod app {
    use vpf::guidance::NavSample;
    use vpf::params::Params;

    use crate::board::stm32f4 as board;
    use crate::firmware::background::{self, BackgroundTask, IdleShared};
    use crate::firmware::link::{Receiver, Transmitter};
    use crate::firmware::mavlink::{MAV_RX_SLOTS, MAV_TX_SLOTS};
    use crate::firmware::periodic::{PeriodShared, PeriodicTask};
    use crate::firmware::sonar::{SONAR_RX_SLOTS, SONAR_TX_SLOTS};
    use crate::firmware::{
        fault, GoalFlown, LinkCounters, Lockstep, Memory, Stats, CONTROL_RX_SLOTS, CONTROL_TX_SLOTS,
    };

    /// Shared by idle (the background) and the periodic task: ceiling = the periodic task's
    /// priority, below the UART's, so no lock ever masks the UART.
    #[shared]
    struct Shared {
        /// The newest navigation (background → periodic).
        nav: Option<NavSample>,
        /// The decoder's and background's counters (background → periodic, for telemetry).
        link_counters: LinkCounters,
        /// Firmware time, ms (periodic → background, for time stamps).
        now_ms: u64,
        /// The waypoint flown to and its generation (periodic → background, for the route).
        goal: GoalFlown,
        /// Lockstep: the host's clock and the `Tick` waiting to run (both ways).
        lockstep: Lockstep,
        /// What the periodic task has done (periodic → the self-test).
        stats: Stats,
    }

    /// Each owned by the one task that uses it.
    #[local]
    struct Local {
        periodic: PeriodicTask,
        background: BackgroundTask,
        /// USART2 and the control link's interrupt ends.
        usart2: (
            board::Usart2,
            Receiver<CONTROL_RX_SLOTS>,
            Transmitter<CONTROL_TX_SLOTS>,
        ),
        /// USART1 and the Ping360 link's interrupt ends.
        usart1: (
            board::Usart1,
            Receiver<SONAR_RX_SLOTS>,
            Transmitter<SONAR_TX_SLOTS>,
        ),
        /// USART6 and the MAVLink link's interrupt ends.
        usart6: (
            board::Usart6,
            Receiver<MAV_RX_SLOTS>,
            Transmitter<MAV_TX_SLOTS>,
        ),
    }

    /// Start-up, interrupts masked: the stack guard, clocks, USART2, SysTick, the cycle
    /// counter and the watchdog, the runtime built in
    /// its statics (`memory` in `.bss`, with the route layer and the evidence map: in `.data`
    /// their initial values took 4.5 KiB of flash), the queues split into their ends.
    #[init(local = [
        memory: Memory = Memory::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        board::log(concat!("vpf-firmware ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
        fault::guard_stack(cx.core.MPU);
        let Some(parts) = board::init(cx.core.SYST, cx.core.DCB, cx.core.DWT) else {
            board::exit(false)
        };
        let Some(fw) = crate::firmware::start(
            cx.local.memory,
            Params::default(),
            parts.timer,
            parts.watchdog,
        ) else {
            board::exit(false)
        };
        (
            Shared {
                nav: None,
                link_counters: LinkCounters::default(),
                now_ms: 0,
                goal: (0, None),
                lockstep: Lockstep::default(),
                stats: Stats::default(),
            },
            Local {
                periodic: fw.periodic,
                background: fw.background,
                usart2: (parts.control, fw.receiver, fw.transmitter),
                usart1: (parts.sonar, fw.sonar_receiver, fw.sonar_transmitter),
                usart6: (parts.mavlink, fw.mav_receiver, fw.mav_transmitter),
            },
        )
    }

    /// The background (thread mode, priority 0): decodes, extracts, maps and routes.
    #[idle(local = [background], shared = [nav, link_counters, now_ms, goal, lockstep, stats])]
    fn idle(cx: idle::Context) -> ! {
        let s = cx.shared;
        let mut shared = IdleShared {
            nav: s.nav,
            link_counters: s.link_counters,
            now_ms: s.now_ms,
            goal: s.goal,
            lockstep: s.lockstep,
            stats: s.stats,
        };
        background::run(cx.local.background, &mut shared)
    }

    /// The periodic task: every SysTick interrupt (absolute schedule), or when idle pends
    /// SysTick for a lockstep `Tick`. At the shared resources' ceiling: its locks are free.
    #[task(binds = SysTick, priority = 2, local = [periodic],
           shared = [nav, link_counters, now_ms, goal, lockstep, stats])]
    fn period(cx: period::Context) {
        let task = cx.local.periodic;
        let s = cx.shared;
        (
            s.nav,
            s.link_counters,
            s.now_ms,
            s.goal,
            s.lockstep,
            s.stats,
        )
            .lock(|nav, link_counters, now_ms, goal, lockstep, stats| {
                task.on_interrupt(PeriodShared {
                    nav,
                    link_counters,
                    now_ms,
                    goal,
                    lockstep,
                    stats,
                });
            });
    }

    /// USART2, both directions: received bytes into the queue while there is room (on a full
    /// queue RX-not-empty goes off until the background has taken bytes), then queued bytes out while
    /// the UART takes them, the transmit-empty interrupt on only while bytes remain.
    #[task(binds = USART2, priority = 3, local = [usart2])]
    fn usart2_both_ways(cx: usart2_both_ways::Context) {
        let (uart, receiver, transmitter) = cx.local.usart2;
        let held = receiver.receive_or_hold(uart);
        uart.listen(!held);
        let more = transmitter.transmit(uart);
        uart.interrupt_when_ready(more);
    }

    /// USART1 (the Ping360), both directions: received bytes into its queue while there is
    /// room (on a full queue RX-not-empty goes off until the background has taken bytes), then
    /// its commands out.
    #[task(binds = USART1, priority = 3, local = [usart1])]
    fn usart1_both_ways(cx: usart1_both_ways::Context) {
        let (uart, receiver, transmitter) = cx.local.usart1;
        let held = receiver.receive_or_hold(uart);
        uart.listen(!held);
        let more = transmitter.transmit(uart);
        uart.interrupt_when_ready(more);
    }

    /// USART6 (MAVLink), both directions: received bytes into its queue (full: dropped,
    /// counted), then queued frames out.
    #[task(binds = USART6, priority = 3, local = [usart6])]
    fn usart6_both_ways(cx: usart6_both_ways::Context) {
        let (uart, receiver, transmitter) = cx.local.usart6;
        receiver.receive(uart);
        let more = transmitter.transmit(uart);
        uart.interrupt_when_ready(more);
    }
}
