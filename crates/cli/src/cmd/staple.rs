//! `interslice staple RATER... --out OUT [--label L] [--probability FILE]
//! [--json]`: the STAPLE consensus (Warfield, Zou & Wells 2004) of several
//! label volumes on one grid, with each rater's estimated sensitivity and
//! specificity.
//!
//! With `--label L` the raters are the masks `v == L` (for 0/1 masks L = 1),
//! one binary run, and OUT is a 0/1 mask. Without it, every label present in
//! any rater gets its own run and OUT paints the consensus labels in
//! ascending order. `--probability` (with `--label`) writes the posterior
//! probability of every voxel as f32, the output of ITK's and SimpleITK's
//! `STAPLEImageFilter`, which `scripts/test-staple.sh` compares with.
use anyhow::{Context, Result, bail};
use interslice_core::staple::{MAX_RATERS, Staple, StapleParams, staple, staple_labels};
use interslice_core::{AnyVolume, LabelVolume, Mask};
use std::path::PathBuf;

/// Arguments of `staple`.
#[derive(clap::Args)]
pub struct Args {
    /// The raters' label volumes (at least 2), on one grid.
    #[arg(required = true, num_args = 2..)]
    pub raters: Vec<PathBuf>,
    /// The consensus label volume to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Only this label (voxels equal to L are foreground). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// With --label: write the posterior probability of every voxel (f32).
    #[arg(long, value_name = "FILE")]
    pub probability: Option<PathBuf>,
    /// Stop after this many EM iterations.
    #[arg(long, default_value_t = StapleParams::default().max_iterations)]
    pub max_iterations: usize,
    /// Print the estimates as JSON.
    #[arg(long)]
    pub json: bool,
}

fn estimate_json(label: u16, names: &[String], s: &Staple) -> serde_json::Value {
    let raters: Vec<serde_json::Value> = names
        .iter()
        .enumerate()
        .map(|(j, n)| {
            serde_json::json!({
                "rater": n,
                "sensitivity": finite(s.sensitivity[j]),
                "specificity": finite(s.specificity[j]),
            })
        })
        .collect();
    serde_json::json!({
        "label": label,
        "prior": s.prior,
        "iterations": s.iterations,
        "converged": s.converged,
        "consensus_voxels": s.consensus.data().iter().filter(|&&b| b).count(),
        "raters": raters,
    })
}

/// NaN (no foreground or no background in the estimate) as JSON null.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    let label = a
        .label_arg
        .as_ref()
        .map(|l| l.resolve(&a.raters.iter().map(|p| p.as_path()).collect::<Vec<_>>()))
        .transpose()?;
    if a.raters.len() > MAX_RATERS {
        bail!(
            "STAPLE takes at most {MAX_RATERS} raters, got {}",
            a.raters.len()
        );
    }
    if a.probability.is_some() && label.is_none() {
        bail!("--probability needs --label (one binary run)");
    }
    let vols: Vec<LabelVolume> = a
        .raters
        .iter()
        .map(|p| interslice_io::read_labels(p).with_context(|| format!("reading {}", p.display())))
        .collect::<Result<_>>()?;
    for (v, p) in vols.iter().zip(&a.raters).skip(1) {
        vols[0]
            .geometry()
            .ensure_same_grid(v.geometry())
            .with_context(|| format!("{} and {} differ", a.raters[0].display(), p.display()))?;
    }
    let names: Vec<String> = a.raters.iter().map(|p| p.display().to_string()).collect();
    let params = StapleParams {
        max_iterations: a.max_iterations.max(1),
        ..Default::default()
    };
    let mut runs = Vec::new();
    if let Some(l) = label {
        let masks: Vec<Mask> = vols.iter().map(|v| v.mask_of(l)).collect();
        let refs: Vec<&Mask> = masks.iter().collect();
        let s = staple(&refs, params, &interslice_core::Cancel::new())?;
        let out: LabelVolume = s.consensus.map(u16::from);
        interslice_io::write_labels(&a.out, &out)
            .with_context(|| format!("writing {}", a.out.display()))?;
        if let Some(p) = &a.probability {
            interslice_io::write_volume(p, &AnyVolume::F32(s.probability(&refs)))
                .with_context(|| format!("writing {}", p.display()))?;
        }
        runs.push((l, s));
    } else {
        let refs: Vec<&LabelVolume> = vols.iter().collect();
        let (out, per) = staple_labels(&refs, params, &interslice_core::Cancel::new())?;
        interslice_io::write_labels(&a.out, &out)
            .with_context(|| format!("writing {}", a.out.display()))?;
        runs = per;
    }
    if a.json {
        let labels: Vec<serde_json::Value> = runs
            .iter()
            .map(|(l, s)| estimate_json(*l, &names, s))
            .collect();
        let v = serde_json::json!({"labels": labels, "out": a.out.display().to_string()});
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    for (l, s) in &runs {
        println!(
            "label {l}: {} iterations{}, prior {:.6}, consensus {} voxels",
            s.iterations,
            if s.converged { "" } else { " (not converged)" },
            s.prior,
            s.consensus.data().iter().filter(|&&b| b).count()
        );
        for (j, n) in names.iter().enumerate() {
            println!(
                "  {n}: sensitivity {:.4}, specificity {:.6}",
                s.sensitivity[j], s.specificity[j]
            );
        }
    }
    println!("wrote {}", a.out.display());
    Ok(())
}
