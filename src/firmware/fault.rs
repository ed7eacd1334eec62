//! Faults: a stack overflow faults instead of corrupting data, and every hard fault is reported.
//!
//! **The stack guard.** The firmware is linked with flip-link (`.cargo/config.toml`), which
//! puts the stack at the bottom of RAM, below `.data` and `.bss`: a stack that overflows leaves
//! RAM instead of running into the queues. Below RAM, [`guard_stack`] makes an 8 KiB MPU region
//! with no access at all, so the first push past the bottom of the stack is a memory-management
//! fault on any board (QEMU's `mps2-an386` would otherwise accept writes there silently), which
//! escalates to the hard fault. A frame larger than 8 KiB could jump the guard; none comes
//! close (the whole stack's high-water mark is reported by the self-test).
//!
//! **The report.** The hard fault handler cannot use the stack it faulted on, so its first
//! instructions move the stack pointer back to the top of the stack region, then call
//! [`report`] with the faulting stack pointer and, when the exception frame is in RAM, the
//! faulting PC. It logs one line and stops the board with a failure status (`tests/qemu.rs`
//! checks this on the emulated board with the `stackcheck` image).

use cortex_m::peripheral::MPU;

use crate::board::active as board;

/// Bottom of RAM on both boards (`boards/*/memory.x`).
const RAM_START: u32 = 0x2000_0000;
/// The guard region's size, log2 (8 KiB, the MPU's region sizes are powers of two).
const GUARD_LOG2: u32 = 13;
/// The guard region: the 8 KiB below RAM (reserved on the STM32F446, unmapped on the AN386).
const GUARD_BASE: u32 = RAM_START - (1 << GUARD_LOG2);

// ARMv7-M MPU register fields.
const MPU_CTRL_ENABLE: u32 = 1 << 0;
const MPU_CTRL_PRIVDEFENA: u32 = 1 << 2;
const RBAR_VALID: u32 = 1 << 4;
const RASR_ENABLE: u32 = 1 << 0;
const RASR_XN: u32 = 1 << 28;
// AP = 0b000 (no access, privileged included): bits 26:24 left clear.

/// Turns the MPU on with one region, the no-access guard below RAM; the rest of the memory map
/// stays as it was (the default map, for privileged code: all of the firmware). The MPU is off
/// in the hard fault handler (HFNMIENA clear), so the report itself cannot fault on the guard.
pub fn guard_stack(mpu: MPU) {
    let rasr = RASR_XN | ((GUARD_LOG2 - 1) << 1) | RASR_ENABLE;
    // # Safety
    // Start-up, interrupts still masked: nothing runs concurrently. Region 0 covers only the
    // 8 KiB below RAM, where the firmware has nothing; PRIVDEFENA keeps the default memory map
    // everywhere else, so no access the firmware makes changes meaning.
    #[allow(unsafe_code)]
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(GUARD_BASE | RBAR_VALID);
        mpu.rasr.write(rasr);
        mpu.ctrl.write(MPU_CTRL_ENABLE | MPU_CTRL_PRIVDEFENA);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

extern "C" {
    /// The stack's lowest address (cortex-m-rt; flip-link sets it to the bottom of RAM).
    static _stack_end: u32;
    /// The stack's top, its initial pointer.
    static _stack_start: u32;
}

// # Safety
// Naked: the hard fault's entry, run with the stack pointer possibly past the guard. It touches
// no stack: it reads MSP, reads the stacked PC only if MSP is at or above the stack's bottom
// (so the frame is in RAM), points SP at the top of the stack region (the faulting context is
// abandoned: `report` never returns) and branches to `report(sp, overflow, pc)`.
#[allow(unsafe_code)]
#[unsafe(naked)]
#[no_mangle]
extern "C" fn HardFault() -> ! {
    core::arch::naked_asm!(
        "mrs r0, msp",
        "movw r3, :lower16:{bottom}",
        "movt r3, :upper16:{bottom}",
        "movs r1, #1",
        "movs r2, #0",
        "cmp r0, r3",
        "blo 1f",
        "movs r1, #0",
        "ldr r2, [r0, #24]",
        "1:",
        "movw r3, :lower16:{top}",
        "movt r3, :upper16:{top}",
        "mov sp, r3",
        "b {report}",
        bottom = sym _stack_end,
        top = sym _stack_start,
        report = sym report,
    )
}

/// Logs the hard fault and stops the board: a fault is never a silent hang.
extern "C" fn report(sp: u32, overflow: u32, pc: u32) -> ! {
    if overflow != 0 {
        let mut line = *b"vpf-firmware: hard fault: stack overflow (sp 0x00000000)\n";
        hex(&mut line, 47, sp);
        board::log(&line);
    } else {
        let mut line = *b"vpf-firmware: hard fault at pc 0x00000000\n";
        hex(&mut line, 33, pc);
        board::log(&line);
    }
    board::exit(false)
}

/// Writes `v` as eight hex digits into `line` from `at`.
fn hex(line: &mut [u8], at: usize, v: u32) {
    let digits = b"0123456789abcdef";
    for (i, slot) in line.iter_mut().skip(at).take(8).enumerate() {
        let nibble = (v >> (28 - 4 * i as u32)) & 0xF;
        *slot = digits.get(nibble as usize).copied().unwrap_or(b'?');
    }
}

/// The `stackcheck` image's test (called only there): recurses until the stack overflows. The
/// guard must turn that into the hard fault's report; the line after the recursion is printed,
/// and the image exits successfully, only if it did not.
pub fn overflow_the_stack() -> ! {
    board::log(b"stackcheck: recursing until the stack overflows\n");
    let mut seed = [1u32; 16];
    let depth = recurse(&mut seed, 0);
    board::log(if depth > 0 {
        b"stackcheck: the recursion returned: no stack guard\n"
    } else {
        b"stackcheck: the recursion returned: no stack guard (0)\n"
    });
    board::exit(true)
}

/// 64 bytes of locals a level, kept live across the call so the frames cannot be folded away.
#[inline(never)]
fn recurse(parent: &mut [u32; 16], depth: u32) -> u32 {
    let mut local = *parent;
    for (i, v) in local.iter_mut().enumerate() {
        *v = v.wrapping_mul(31).wrapping_add(depth ^ i as u32);
    }
    core::hint::black_box(&mut local);
    if depth == u32::MAX {
        return local.iter().fold(0u32, |a, &v| a ^ v);
    }
    let below = recurse(&mut local, depth + 1);
    below ^ local.iter().fold(0u32, |a, &v| a.wrapping_add(v))
}
