//! `interslice info FILE`: dims, spacing, type, range, labels.
use std::path::PathBuf;

/// Arguments of `info`.
#[derive(clap::Args)]
pub struct Args {
    /// The volume file or slice folder.
    pub input: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Run `info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::bail!("cannot read {}: file formats are not implemented yet (json={})", args.input.display(), args.json)
}
