//! `ehservo fmu`, `schema` and `defaults`: what the program hands to other tools
//! (an FMU, the JSON Schemas of its file formats, the default scenario).

use super::{load, StdoutError};
use crate::scenario::Scenario;
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;

/// `ehservo fmu`.
#[derive(clap::Args)]
pub(super) struct FmuArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// The FMU to write (e.g. controller.fmu).
    #[arg(long)]
    out: PathBuf,
    /// Export the closed loop (plant, actuator, sensors and controller; no inputs) instead of the controller alone.
    #[arg(long)]
    closed_loop: bool,
    /// Export the plant with its actuator (input u, and the load on a cylinder; outputs x and the pressures) instead of the controller.
    #[arg(long, conflicts_with = "closed_loop")]
    plant: bool,
    /// The FMU's binary (default: libehservo_ffi.so beside this ehservo; build it with cargo build -p ehservo-ffi).
    #[arg(long)]
    binary: Option<PathBuf>,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
}

/// `ehservo schema`.
#[derive(clap::Args)]
pub(super) struct SchemaArgs {
    /// The format.
    #[arg(value_enum, default_value = "scenario")]
    format: crate::schema::Format,
    /// Print the reference page (Markdown) instead.
    #[arg(long)]
    markdown: bool,
}

/// `ehservo fmu`.
pub(super) fn fmu(a: FmuArgs) -> Result<()> {
    let FmuArgs {
        scenario,
        out,
        closed_loop,
        plant,
        binary,
        set,
    } = a;
    use crate::fmu::{write_fmu, FmuKind};
    let lp = load(&scenario, &set)?;
    let s = lp.scenario();
    let kind = match (closed_loop, plant) {
        (true, _) => FmuKind::ClosedLoop,
        (_, true) => FmuKind::Plant,
        _ => FmuKind::Controller,
    };
    // The destination first (a directory, a missing folder), then
    // the binary: both before any work.
    crate::fmu::check_out(&out)?;
    if out.extension().and_then(|e| e.to_str()) != Some("fmu") {
        crate::bad_input!("--out {}: an FMU's file name ends in .fmu", out.display());
    }
    let Some(binary) = binary.or_else(crate::fmu::default_binary) else {
        crate::bad_input!(
            "the FMU's binary libehservo_ffi.so is not beside this ehservo: build it (cargo build -p ehservo-ffi, same profile) or pass --binary PATH"
        );
    };
    write_fmu(&out, kind, &lp, &binary)?;
    note!(
        "{}: the {} FMU of {} (FMI 3.0 co-simulation, step {} s)",
        out.display(),
        kind.as_str(),
        s.name,
        s.simulation.step
    );
    Ok(())
}

/// `ehservo schema`.
pub(super) fn schema(a: SchemaArgs, w: &mut impl Write) -> Result<()> {
    let SchemaArgs { format, markdown } = a;
    if markdown {
        put!(w, "{}", crate::schema::markdown(format));
    } else {
        put!(w, "{}", crate::schema::schema_text(format));
    }
    Ok(())
}

/// `ehservo defaults`.
pub(super) fn defaults(w: &mut impl Write) -> Result<()> {
    let s = Scenario {
        name: "fig2".into(),
        description: "The paper's Fig. 2 case (every default).".into(),
        ..Scenario::default()
    };
    put!(w, "{}", s.to_toml());
    Ok(())
}
