//! `interslice variability DIR [--label L] [--out OUT] [--method M]
//! [--consensus-dir D]`: how much the tracers of a project disagree, and
//! what they agree on. The measurement and the report files are
//! `interslice_project::report::variability` (see there for what is written).
use anyhow::Result;
use interslice_project::report::variability::{self, Options};
use std::path::PathBuf;

/// Arguments of `variability`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub project: crate::project::ProjectArgs,
    /// Only this label (1 cell, 2 nucleus, ...). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// Output folder (default DIR/variability).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Interpolation method of the tracings (default: the default interpolator).
    #[arg(long)]
    pub method: Option<String>,
    /// Where the consensus label volumes go (default OUT/consensus).
    #[arg(long, value_name = "D")]
    pub consensus_dir: Option<PathBuf>,
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    let store = a.project.open_existing()?;
    let label = crate::project::resolve_label(&store, a.label_arg.as_ref())?;
    let options = Options {
        dir: a.project.dir,
        label,
        out: a.out,
        method: a.method,
        consensus_dir: a.consensus_dir,
    };
    let s = variability::run(&store, &options, &mut |line| eprintln!("{line}"))?;
    println!(
        "{} structure(s) of {} cell(s) -> {}",
        s.structures,
        s.cells,
        s.out.display()
    );
    Ok(())
}
