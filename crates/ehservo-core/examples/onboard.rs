//! The firmware's loop on the host: the Fig. 2 case closed at a fixed rate
//! in f32 or f64, printing what `examples/firmware-m4f` prints on the board
//! (checkpoints every simulated second, then e_max), so the two can be
//! compared line for line.
//!
//! ```sh
//! cargo run -p ehservo-core --example onboard -- f32 10000
//! ```

use ehservo_core::math::Real;
use ehservo_core::onboard::Fig2Loop;

fn run<T: Real>(rate: u32, seconds: u32) -> Result<(), String> {
    let mut lp = Fig2Loop::<T>::paper(rate).map_err(|e| e.to_string())?;
    println!(
        "ehservo onboard: Fig. 2 NNBVSC, {} at {rate} Hz, {seconds} s",
        T::NAME
    );
    for s in 0..seconds {
        lp.run_for(s + 1)
            .map_err(|k| format!("non-finite state or command at k = {k}"))?;
        println!("{}", lp.checkpoint());
    }
    println!("e_max_deg={:?}", lp.e_max_deg());
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ty = args.first().map(String::as_str).unwrap_or("f32");
    let rate = match args.get(1).map(|s| s.parse::<u32>()) {
        None => 10_000,
        Some(Ok(r)) if r > 0 => r,
        Some(_) => {
            eprintln!("error: the rate (second argument) must be a whole number of hertz > 0");
            std::process::exit(2);
        }
    };
    let seconds = 10;
    let r = match ty {
        "f32" => run::<f32>(rate, seconds),
        "f64" => run::<f64>(rate, seconds),
        other => {
            eprintln!("error: the float type (first argument) must be f32 or f64, not {other:?}");
            std::process::exit(2);
        }
    };
    if let Err(e) = r {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
