//! The paper's Fig. 2 case closed on an (emulated) Cortex-M4F: the sampled
//! NNBVSC at 10 kHz against the plant, 10 s of simulated time, output over
//! semihosting. Runs in QEMU's `mps2-an386`: `cargo run --release` here
//! (`--features f64` for the f64 build), `run.sh` for CI, `measure.sh` for
//! the instruction counts and sizes.
//!
//! Output, line by line:
//! - a header (`# ...`);
//! - `checkpoint k=… t=… x1=… e=… u=…` every 1 s of simulated time
//!   ([`ehservo_core::onboard::Checkpoint`]) and `e_max_deg=…` at the end:
//!   these lines are the host's (`--example onboard`) to the bit, floats
//!   printed with `{:?}` (shortest round-trip);
//! - `timing: …`, `calib: …`, `stack: …`: SysTick readings (meaningful as
//!   instruction counts only under `qemu -icount shift=0`, see measure.sh),
//!   the stack high-water mark and the loop's size (it lives on the stack).
//!
//! The number of steps defaults to 100 000 and can be given as the last
//! word of the semihosting command line (`qemu … -append 500`).

#![no_std]
#![no_main]

use core::arch::asm;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln, nr};
use panic_semihosting as _;

use ehservo_core::onboard::Fig2Loop;

#[cfg(not(feature = "f64"))]
type F = f32;
#[cfg(feature = "f64")]
type F = f64;
const FLOAT: &str = if cfg!(feature = "f64") { "f64" } else { "f32" };

/// Sample rate (Hz) and the default run: 10 s of simulated time.
const RATE_HZ: u32 = 10_000;
const DEFAULT_STEPS: u32 = 10 * RATE_HZ;

/// SysTick is a 24-bit down-counter.
const SYST_MASK: u32 = 0x00FF_FFFF;

/// Steps whose SysTick delta is printed one by one (for the exact
/// cross-check of measure.sh), when the run is this short.
const VERBOSE_STEPS: u32 = 20;

#[entry]
fn main() -> ! {
    let steps = steps_from_cmdline().unwrap_or(DEFAULT_STEPS);
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut syst = cp.SYST;
    // Processor clock: on mps2-an386 QEMU runs it from the 25 MHz SYSCLK.
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYST_MASK);
    syst.clear_current();
    syst.enable_counter();

    hprintln!(
        "# ehservo firmware-m4f: Fig2Loop<{}> at {} Hz, {} steps",
        FLOAT,
        RATE_HZ,
        steps
    );

    let mut lp = match Fig2Loop::<F>::paper(RATE_HZ) {
        Ok(lp) => lp,
        Err(e) => fail(format_args!("parameters rejected: {}", e)),
    };

    let (mut ctl_total, mut ctl_max, mut ctl_max_k) = (0u64, 0u32, 0u32);
    let (mut adv_total, mut sense_total, mut sense_max) = (0u64, 0u64, 0u32);
    for _ in 0..steps {
        let k = lp.k();
        let ts = SYST::get_current();
        let z = sense_step(&mut lp);
        let t0 = SYST::get_current();
        let u = control_step(&mut lp, z);
        let t1 = SYST::get_current();
        advance_step(&mut lp, u);
        let t2 = SYST::get_current();

        let ds = ts.wrapping_sub(t0) & SYST_MASK;
        sense_total += ds as u64;
        sense_max = sense_max.max(ds);

        let d = t0.wrapping_sub(t1) & SYST_MASK;
        ctl_total += d as u64;
        if d > ctl_max {
            (ctl_max, ctl_max_k) = (d, k);
        }
        adv_total += (t1.wrapping_sub(t2) & SYST_MASK) as u64;
        if steps <= VERBOSE_STEPS {
            hprintln!("step: k={} control_ticks={}", k, d);
        }

        let x = lp.x();
        if !(u.is_finite() && x.iter().all(|v| v.is_finite())) {
            fail(format_args!("non-finite at k={}: u={:?} x={:?}", k, u, x));
        }
        if lp.k() % RATE_HZ == 0 {
            hprintln!("{}", lp.checkpoint());
        }
    }
    hprintln!("e_max_deg={:?}", lp.e_max_deg());

    hprintln!(
        "timing: control() SysTick ticks: steps={} total={} max={} max_at_k={}",
        steps,
        ctl_total,
        ctl_max,
        ctl_max_k
    );
    hprintln!(
        "timing: sense() SysTick ticks: total={} max={}",
        sense_total,
        sense_max
    );
    hprintln!("timing: advance() SysTick ticks: total={}", adv_total);
    // Two counted loops of 2n instructions each (subs + bne): under
    // -icount shift=0 their ticks give the instructions per tick (measure.sh
    // checks it). Skipped on the short runs that measure.sh traces.
    if steps > VERBOSE_STEPS {
        let mut ticks = 0;
        for n in [250_000u32, 2_500_000] {
            let t0 = SYST::get_current();
            nop_loop(n);
            let t1 = SYST::get_current();
            ticks = t0.wrapping_sub(t1) & SYST_MASK;
            hprintln!("calib: loop_insns={} ticks={}", 2 * n, ticks);
        }
        // 5e6 instructions are 125 000 ticks (+-1) only when virtual time
        // is instruction count (-icount shift=0); otherwise it is host time.
        let icount = ticks.abs_diff(125_000) <= 1;
        hprintln!(
            "calib: SysTick counts 40 instructions per tick here: {}",
            if icount {
                "yes (-icount shift=0): the ticks above are instructions/40"
            } else {
                "no (not under -icount shift=0): the ticks above follow host time, not instructions"
            }
        );
    }
    let (used, size) = stack_high_water();
    hprintln!(
        "stack: high_water_bytes={} of {} (Fig2Loop<{}> on it: {} bytes)",
        used,
        size,
        FLOAT,
        core::mem::size_of::<Fig2Loop<F>>()
    );

    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

/// The controller step proper (`SampledController::step`: measurement
/// checks, the NNBVSC law, forward Euler on ∫e and W), kept out of line so
/// that its entry and return can be found in a trace (measure.sh).
#[inline(never)]
fn control_step(lp: &mut Fig2Loop<F>, z: [F; 4]) -> F {
    lp.law_step(z)
}

/// The reference z(t) (θd and its three derivatives: one sin/cos pair) and
/// the error bookkeeping: timed apart from the controller step.
#[inline(never)]
fn sense_step(lp: &mut Fig2Loop<F>) -> [F; 4] {
    lp.sense()
}

/// The plant's half of one sample.
#[inline(never)]
fn advance_step(lp: &mut Fig2Loop<F>, u: F) {
    lp.advance(u)
}

/// Exactly 2·n instructions (n ≥ 1): `subs` and `bne`, n times.
#[inline(never)]
fn nop_loop(n: u32) {
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

/// The number of steps, when the command line's last word is one.
fn steps_from_cmdline() -> Option<u32> {
    let mut buf = [0u8; 256];
    let mut block = [buf.as_mut_ptr() as usize, buf.len() - 1];
    // SAFETY: SYS_GET_CMDLINE writes at most block[1] bytes (plus a NUL)
    // into buf and the length into block[1]; both outlive the call.
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if r != 0 {
        return None;
    }
    let len = block[1].min(buf.len());
    let s = core::str::from_utf8(&buf[..len]).ok()?;
    s.split_ascii_whitespace().last()?.parse().ok()
}

/// Bytes of stack ever used (cortex-m-rt painted it with 0xCCCC_CCCC at
/// reset), and the stack's size.
fn stack_high_water() -> (usize, usize) {
    extern "C" {
        static mut _stack_start: u32;
        static mut _stack_end: u32;
    }
    // SAFETY: only the addresses of the linker's symbols are taken, and the
    // words between them (RAM this program owns) are read.
    unsafe {
        let top = core::ptr::addr_of!(_stack_start) as usize;
        let mut p = core::ptr::addr_of!(_stack_end);
        let bottom = p as usize;
        while (p as usize) < top && core::ptr::read_volatile(p) == cortex_m_rt::STACK_PAINT_VALUE {
            p = p.add(1);
        }
        (top - p as usize, top - bottom)
    }
}

fn fail(msg: core::fmt::Arguments) -> ! {
    hprintln!("error: {}", msg);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}
