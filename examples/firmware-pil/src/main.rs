//! Processor-in-the-loop firmware for QEMU's `mps2-an386` (Cortex-M4F).
//!
//! It runs whatever controller the host's handshake describes
//! ([`ehservo_wire::msg::Hello`]: any kind the core builds, in f32 or f64)
//! and answers each measurement frame with the command, the law's parts and
//! the SysTick ticks its `SampledController::step` took. Nothing of a
//! scenario is compiled in: `ehservo pil SCENARIO --qemu` starts QEMU with
//! this ELF and its UART0 on a TCP socket (docs/pil.md).
//!
//! - UART0: the CMSDK APB UART at 0x4000_4000, which QEMU attaches to its
//!   first `-serial` backend. Reception waits in `WFI` for the UART's RX
//!   interrupt (IRQ 0, masked by PRIMASK: it wakes the core, no handler
//!   runs); transmission polls the TX-full bit.
//! - Timing: SysTick on the processor clock, a 24-bit down-counter read
//!   around the step. At boot a counted loop (`subs`/`bne`, 2·n
//!   instructions) calibrates cycles per tick: under `qemu -icount
//!   shift=0` one instruction is one 1 ns cycle and SysTick counts at
//!   25 MHz, so 40 (reported in the Welcome, `ClockInfo`).
//! - Panics end QEMU through semihosting with a failure status.

#![no_std]
#![no_main]

use core::arch::asm;
use core::ptr::{read_volatile, write_volatile};

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use panic_semihosting as _;

use ehservo_wire::board::Board;
use ehservo_wire::frame::{Deframer, Pushed, MAX_FRAME};
use ehservo_wire::law::Ticks;
use ehservo_wire::msg::{ClockInfo, TickSource};

const FIRMWARE: &str = concat!("ehservo-firmware-pil ", env!("CARGO_PKG_VERSION"), " mps2-an386");

/// The CMSDK APB UART0 of the MPS2 (AN386).
mod uart {
    use super::*;
    const BASE: usize = 0x4000_4000;
    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const INTCLEAR: usize = 0x0C;
    const BAUDDIV: usize = 0x10;
    const STATE_TX_FULL: u32 = 1;
    const STATE_RX_FULL: u32 = 2;
    const CTRL_TX_EN: u32 = 1;
    const CTRL_RX_EN: u32 = 2;
    const CTRL_RX_INT_EN: u32 = 8;
    const INT_RX: u32 = 2;
    /// NVIC set-enable and clear-pending registers, IRQ 0 (UART0 RX).
    const NVIC_ISER0: usize = 0xE000_E100;
    const NVIC_ICPR0: usize = 0xE000_E280;

    fn reg(off: usize) -> *mut u32 {
        (BASE + off) as *mut u32
    }

    /// TX and RX on, the RX interrupt enabled at the UART and the NVIC
    /// (and masked by PRIMASK: it only wakes `WFI`).
    pub fn init() {
        cortex_m::interrupt::disable();
        // SAFETY: the UART's and the NVIC's registers (fixed addresses of
        // the AN386 memory map and the Armv7-M system space); nothing else
        // touches them.
        unsafe {
            write_volatile(reg(BAUDDIV), 16);
            write_volatile(reg(CTRL), CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
            write_volatile(NVIC_ISER0 as *mut u32, 1);
        }
    }

    /// The next byte received, sleeping until there is one.
    pub fn read() -> u8 {
        // SAFETY: as in `init`.
        unsafe {
            while read_volatile(reg(STATE)) & STATE_RX_FULL == 0 {
                cortex_m::asm::wfi();
            }
            let b = read_volatile(reg(DATA)) as u8;
            write_volatile(reg(INTCLEAR), INT_RX);
            write_volatile(NVIC_ICPR0 as *mut u32, 1);
            b
        }
    }

    /// Sends `bytes`.
    pub fn write(bytes: &[u8]) {
        for &b in bytes {
            // SAFETY: as in `init`.
            unsafe {
                while read_volatile(reg(STATE)) & STATE_TX_FULL != 0 {}
                write_volatile(reg(DATA), u32::from(b));
            }
        }
    }
}

/// SysTick is a 24-bit down-counter.
const SYST_MASK: u32 = 0x00FF_FFFF;

struct SysTickTicks;

impl Ticks for SysTickTicks {
    #[inline(always)]
    fn now(&mut self) -> u32 {
        SYST::get_current()
    }
    #[inline(always)]
    fn since(&mut self, start: u32) -> u32 {
        start.wrapping_sub(SYST::get_current()) & SYST_MASK
    }
}

/// Exactly 2·n instructions (n ≥ 1): `subs` and `bne`, n times.
#[inline(never)]
fn counted_loop(n: u32) {
    // SAFETY: register-only arithmetic and a local branch.
    unsafe {
        asm!(
            "2:",
            "subs {0}, {0}, #1",
            "bne 2b",
            inout(reg) n => _,
            options(nomem, nostack)
        );
    }
}

/// Cycles per SysTick tick × 1000 from a loop of 5·10⁶ instructions (one
/// cycle each under QEMU's icount; on hardware `subs`/`bne` take 1 and 2–4
/// cycles, so use a DWT-timed build there).
fn calibrate() -> u32 {
    let n = 2_500_000u32;
    let t0 = SYST::get_current();
    counted_loop(n);
    let ticks = t0.wrapping_sub(SYST::get_current()) & SYST_MASK;
    if ticks == 0 {
        return 0;
    }
    ((2 * u64::from(n) * 1000) / u64::from(ticks)) as u32
}

#[entry]
fn main() -> ! {
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYST_MASK);
    syst.clear_current();
    syst.enable_counter();
    uart::init();

    let clock = ClockInfo {
        source: TickSource::SysTick,
        // mps2-an386's SYSCLK, which QEMU gives the processor clock.
        tick_hz: 25_000_000,
        cycles_per_tick_milli: calibrate(),
    };
    let mut board = Board::new(FIRMWARE, clock);
    let mut out = [0u8; MAX_FRAME];
    // A zero first: whatever the host's reader held is ended there.
    uart::write(&[0]);
    let n = board.boot_frame(&mut out);
    uart::write(&out[..n]);

    let mut rx: Deframer<MAX_FRAME> = Deframer::new();
    let mut ticks = SysTickTicks;
    loop {
        let n = match rx.push(uart::read()) {
            Pushed::Nothing => continue,
            Pushed::Frame(len) => board.on_frame(rx.frame(len), &mut ticks, &mut out),
            Pushed::Overrun => board.overrun(&mut out),
        };
        uart::write(&out[..n]);
    }
}
