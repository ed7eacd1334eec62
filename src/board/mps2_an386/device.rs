//! The emulated board as RTIC sees a device: its interrupt numbers, its priority bits and its
//! interrupt vector (what an svd2rust PAC would supply; there is none for the AN386).
//!
//! Interrupt numbers are the AN386's (ARM's "Cortex-M4 FPGA image" application note, and QEMU's
//! `mps2-an386`): each CMSDK APB UART has a receive and a transmit interrupt. UART0 carries the
//! control link, UART1 the Ping360, UART2 MAVLink; the ethernet controller's interrupt (13)
//! carries the control link's frames on QEMU (`eth.rs`).

/// Priority bits the NVIC implements: the AN386 image's 3 (CMSIS `__NVIC_PRIO_BITS`).
pub const NVIC_PRIO_BITS: u8 = 3;

/// The board's external interrupts that the firmware uses (or may).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types, clippy::upper_case_acronyms)]
pub enum Interrupt {
    /// UART0 receive (the control link).
    UART0RX = 0,
    /// UART0 transmit.
    UART0TX = 1,
    /// UART1 receive (the Ping360).
    UART1RX = 2,
    /// UART1 transmit.
    UART1TX = 3,
    /// UART2 receive (MAVLink).
    UART2RX = 4,
    /// UART2 transmit.
    UART2TX = 5,
    /// The ethernet controller (LAN9220; QEMU's LAN9118).
    ETHERNET = 13,
}

/// RTIC names bound interrupts through `device::interrupt::NAME`, as svd2rust PACs export them.
pub use self::Interrupt as interrupt;

// # Safety
// `number` returns the variant's discriminant, a valid AN386 interrupt number (below its 32
// external interrupts), and is the same every call: what `InterruptNumber` requires.
#[allow(unsafe_code)]
unsafe impl cortex_m::interrupt::InterruptNumber for Interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

// The handlers RTIC defines for bound tasks (`#[no_mangle]`); `device.x` (written by build.rs)
// points the unbound ones at cortex-m-rt's `DefaultHandler`.
extern "C" {
    fn UART0RX();
    fn UART0TX();
    fn UART1RX();
    fn UART1TX();
    fn UART2RX();
    fn UART2TX();
    fn ETHERNET();
    /// cortex-m-rt's handler for interrupts nobody binds.
    fn DefaultHandler();
}

/// The device part of the vector table: external interrupts 0–13 (those not listed above are
/// never enabled).
#[allow(unsafe_code)] // `link_section` and `no_mangle` place the table; it only holds addresses.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [unsafe extern "C" fn(); 14] = [
    UART0RX,
    UART0TX,
    UART1RX,
    UART1TX,
    UART2RX,
    UART2TX,
    DefaultHandler,
    DefaultHandler,
    DefaultHandler,
    DefaultHandler,
    DefaultHandler,
    DefaultHandler,
    DefaultHandler,
    ETHERNET,
];
