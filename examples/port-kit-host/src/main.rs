//! `port-kit-host KIT OUT`: runs a GI Lab port kit knowing nothing but the kit and writes every
//! pass's outputs under OUT for `gi-lab verify --port-kit KIT --outputs OUT` (docs/port-kit.md).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [kit, out] = args.as_slice() else {
        eprintln!(
            "usage: port-kit-host KIT OUT\n  runs the port kit KIT (gi-lab export --port-kit) and writes each pass's outputs under OUT"
        );
        return ExitCode::from(2);
    };
    match port_kit_host::run(&PathBuf::from(kit), &PathBuf::from(out)) {
        Ok(s) => {
            println!(
                "{}: {} frames, {} passes, {} steps, {} outputs written to {out} ({})",
                s.preset, s.frames, s.passes, s.steps, s.outputs, s.adapter
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("port-kit-host: {e}");
            ExitCode::FAILURE
        }
    }
}
