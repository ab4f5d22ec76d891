//! The library example of docs/guide/board.md, compiled (and run) by `cargo test`: the
//! NNBVSC of the paper at 10 kHz through the hardware loop, against a crude
//! plant stand-in.

use ehservo_core::prelude::*;

fn main() -> Result<(), Box<dyn core::error::Error>> {
    let model = NominalModel::new(ServoParams::paper(), Load::paper());
    let nn = NnVsc::try_new(
        model,
        SwitchingSurface::paper(),
        NnVscParams::paper(),
        Rbf::paper(),
    )?;
    let mut ctl = SampledController::new(nn, 1e-4)?; // 10 kHz
    let reference = Sine::paper();
    let (theta, theta_dot, theta_ddot) = (0.0, 0.0, 0.0); // read from the sensors
    for k in 0..10 {
        let t = k as f64 * 1e-4;
        let out = ctl.step(t, [theta, theta_dot, theta_ddot], reference.z(t));
        // out.u is the valve command; out.u_eq, out.u_sw, out.sigma, out.wphi … its parts
        assert!(out.u.is_finite());
        if k == 0 {
            println!(
                "u = {:.4} V (u_eq {:.4}, u_sw {:.4})",
                out.u, out.u_eq, out.u_sw
            );
        }
    }
    Ok(())
}
