//! `gi-lab verify`: a port's per-pass outputs against a port kit's goldens (docs/port-kit.md,
//! "Verifying a port").

use std::path::PathBuf;

use clap::Args;

use crate::error::CliError;

#[derive(Args, Debug, Clone)]
pub struct VerifyArgs {
    /// The port kit (`gi-lab export --port-kit`).
    #[arg(long)]
    pub port_kit: PathBuf,
    /// The port's outputs: `frame-K/NN-pass/resource.bin` as the manifest's goldens name them.
    #[arg(long)]
    pub outputs: PathBuf,
    /// The largest FLIP, relative error or share of differing words a pass's output may have.
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
}

/// Prints the table; exits 1 naming the first pass that diverges, 2 on a missing or malformed
/// output.
pub(super) fn verify(a: &VerifyArgs) -> Result<(), CliError> {
    if !(a.tolerance.is_finite() && a.tolerance >= 0.0) {
        return Err(CliError::input(format!("--tolerance {} must be a number ≥ 0", a.tolerance)));
    }
    let report = gi_render::export::port_kit::verify::verify(&a.port_kit, &a.outputs, a.tolerance)
        .map_err(|e| CliError::input(format!("verify: {e}")))?;
    print!("{}", report.table());
    match report.first_divergence() {
        None => {
            println!("all {} outputs are within {}", report.rows.len(), a.tolerance);
            Ok(())
        }
        Some(r) => Err(CliError::failure(format!(
            "the port diverges first at frame {}, pass {:02} {}: {} has {} {:.5} > {}",
            r.frame, r.index, r.pass, r.resource, r.metric, r.value, a.tolerance
        ))),
    }
}
