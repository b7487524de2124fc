//! `interslice variability DIR [--label L] [--out OUT] [--method M]
//! [--consensus-dir D]`: how much the tracers of a project disagree, and
//! what they agree on. The measurement and the report files are
//! `interslice_project::report::variability` (see there for what is written).
use anyhow::{Context, Result, bail};
use interslice_project::report::variability::{self, Options};
use interslice_store::Store;
use std::path::PathBuf;

/// Arguments of `variability`.
#[derive(clap::Args)]
pub struct Args {
    /// The project folder (what `interslice serve DIR` serves).
    pub dir: PathBuf,
    /// Only this label (1 cell, 2 nucleus, ...). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// `--label` resolved to its value (set by `run`).
    #[arg(skip)]
    pub label: Option<u16>,
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
pub fn run(mut a: Args) -> Result<()> {
    if !a.dir.is_dir() {
        bail!("{} is not a folder", a.dir.display());
    }
    let db = interslice_store::default_db_path(&a.dir);
    if !db.is_file() {
        bail!(
            "{} has no annotation database ({}); trace with `interslice serve` first",
            a.dir.display(),
            db.display()
        );
    }
    let store = Store::open(&db).with_context(|| format!("opening {}", db.display()))?;
    let components = store.components()?;
    a.label = a
        .label_arg
        .as_ref()
        .map(|l| l.resolve_in(&components))
        .transpose()?;
    let options = Options {
        dir: a.dir,
        label: a.label,
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
