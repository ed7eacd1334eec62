//! The firmware's contexts on the emulated board, declared as an RTIC application: which task
//! runs at which priority, bound to which interrupt, owning or sharing what. The bodies are the
//! firmware's ([`crate::firmware`]); the NUCLEO's application (`board::stm32f4::app`) differs
//! only in its UART task and start-up.

#[rtic::app(device = crate::board::mps2_an386::device, peripherals = false)]
mod app {
    use vpf::guidance::NavSample;
    use vpf::params::Params;

    use crate::board::mps2_an386 as board;
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
        /// The control link's receiving end, for UART0 and the ethernet controller (both at
        /// priority 3: the lock is free and masks nothing).
        control_rx: Receiver<CONTROL_RX_SLOTS>,
        /// The control link's sending end, likewise.
        control_tx: Transmitter<CONTROL_TX_SLOTS>,
    }

    /// Each owned by the one task that uses it.
    #[local]
    struct Local {
        periodic: PeriodicTask,
        background: BackgroundTask,
        /// UART0's receive half.
        uart0_rx: board::UartRx,
        /// UART0's transmit half.
        uart0_tx: board::UartTx,
        /// The ethernet controller, if it came up.
        ethernet: Option<board::eth::Ethernet>,
        /// UART1's receive half and the Ping360 link's receiving end.
        uart1_rx: (board::UartRx, Receiver<SONAR_RX_SLOTS>),
        /// UART1's transmit half and the Ping360 link's sending end.
        uart1_tx: (board::UartTx, Transmitter<SONAR_TX_SLOTS>),
        /// UART2's receive half and the MAVLink link's receiving end.
        uart2_rx: (board::UartRx, Receiver<MAV_RX_SLOTS>),
        /// UART2's transmit half and the MAVLink link's sending end.
        uart2_tx: (board::UartTx, Transmitter<MAV_TX_SLOTS>),
    }

    /// Start-up, interrupts masked: the stack guard, UART0 and SysTick, the runtime built in
    /// its statics (`memory` in `.bss`, with the route layer and the evidence map: in `.data`
    /// their initial values took 4.5 KiB of flash), the queues split into their ends.
    #[init(local = [
        memory: Memory = Memory::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        board::log(concat!("vpf-firmware ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
        fault::guard_stack(cx.core.MPU);
        let Some(parts) = board::init(cx.core.SYST) else {
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
        let (uart_rx, uart_tx) = parts.control;
        let (sonar_rx, sonar_tx) = parts.sonar;
        let (mav_rx, mav_tx) = parts.mavlink;
        (
            Shared {
                nav: None,
                link_counters: LinkCounters::default(),
                now_ms: 0,
                goal: (0, None),
                lockstep: Lockstep::default(),
                stats: Stats::default(),
                control_rx: fw.receiver,
                control_tx: fw.transmitter,
            },
            Local {
                periodic: fw.periodic,
                background: fw.background,
                uart0_rx: uart_rx,
                uart0_tx: uart_tx,
                ethernet: parts.ethernet,
                uart1_rx: (sonar_rx, fw.sonar_receiver),
                uart1_tx: (sonar_tx, fw.sonar_transmitter),
                uart2_rx: (mav_rx, fw.mav_receiver),
                uart2_tx: (mav_tx, fw.mav_transmitter),
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

    /// UART0 receive: bytes into the control link's queue while there is room; on a full queue
    /// the byte stays in the UART and the interrupt goes off until the background has taken
    /// bytes (it pends this task again). The host is on UART0.
    #[task(binds = UART0RX, priority = 3, local = [uart0_rx], shared = [control_rx])]
    fn uart0_receive(mut cx: uart0_receive::Context) {
        let uart = cx.local.uart0_rx;
        uart.acknowledge();
        board::eth::host_left();
        let held = cx
            .shared
            .control_rx
            .lock(|receiver| receiver.receive_or_hold(uart));
        uart.listen(!held);
    }

    /// UART0 transmit: queued bytes out while the UART takes them; the interrupt stays on only
    /// while bytes remain.
    #[task(binds = UART0TX, priority = 3, local = [uart0_tx], shared = [control_tx])]
    fn uart0_transmit(mut cx: uart0_transmit::Context) {
        let uart = cx.local.uart0_tx;
        uart.acknowledge();
        let more = cx
            .shared
            .control_tx
            .lock(|transmitter| transmitter.transmit(uart));
        uart.interrupt_when_ready(more);
    }

    /// The ethernet controller: received frames into the control link's queue, queued bytes
    /// out in frames when the host is on this link (pended by `kick_tx`, and by the background
    /// when a frame waited for room).
    #[task(binds = ETHERNET, priority = 3, local = [ethernet], shared = [control_rx, control_tx])]
    fn ethernet(cx: ethernet::Context) {
        let Some(eth) = cx.local.ethernet.as_mut() else {
            return;
        };
        (cx.shared.control_rx, cx.shared.control_tx)
            .lock(|receiver, transmitter| eth.on_interrupt(receiver, transmitter));
    }

    /// UART1 receive (the Ping360): bytes into its queue while there is room; on a full queue
    /// the byte stays in the UART and the interrupt goes off until the background has taken
    /// bytes (it pends this task again).
    #[task(binds = UART1RX, priority = 3, local = [uart1_rx])]
    fn uart1_receive(cx: uart1_receive::Context) {
        let (uart, receiver) = cx.local.uart1_rx;
        uart.acknowledge();
        let held = receiver.receive_or_hold(uart);
        uart.listen(!held);
    }

    /// UART1 transmit: the Ping360's commands out.
    #[task(binds = UART1TX, priority = 3, local = [uart1_tx])]
    fn uart1_transmit(cx: uart1_transmit::Context) {
        let (uart, transmitter) = cx.local.uart1_tx;
        uart.acknowledge();
        let more = transmitter.transmit(uart);
        uart.interrupt_when_ready(more);
    }

    /// UART2 receive (MAVLink): every waiting byte into its queue (full: dropped, counted).
    #[task(binds = UART2RX, priority = 3, local = [uart2_rx])]
    fn uart2_receive(cx: uart2_receive::Context) {
        let (uart, receiver) = cx.local.uart2_rx;
        uart.acknowledge();
        receiver.receive(uart);
    }

    /// UART2 transmit: MAVLink frames out.
    #[task(binds = UART2TX, priority = 3, local = [uart2_tx])]
    fn uart2_transmit(cx: uart2_transmit::Context) {
        let (uart, transmitter) = cx.local.uart2_tx;
        uart.acknowledge();
        let more = transmitter.transmit(uart);
        uart.interrupt_when_ready(more);
    }
}
