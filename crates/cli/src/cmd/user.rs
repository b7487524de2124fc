//! `interslice user add NAME [--dir DIR] [--reviewer]` and
//! `interslice user list [--dir DIR]`: accounts of a project's annotation
//! database (DIR defaults to the current folder, the project being served).
//!
//! The password is read from the `INTERSLICE_PASSWORD` environment variable or
//! from the first line of standard input, never from the command line (which
//! other users can see in the process list).
use anyhow::{Result, bail};
use interslice_store::{Role, Store};
use std::io::BufRead as _;
use std::path::PathBuf;

/// Arguments of `user`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    action: Action,
}

#[derive(clap::Subcommand)]
enum Action {
    /// Create an account, or change its password and role.
    Add {
        /// The user name.
        name: String,
        /// The project folder.
        #[arg(long, default_value = ".")]
        dir: PathBuf,
        /// The user reads everyone's tracings (reviewer role).
        #[arg(long)]
        reviewer: bool,
        /// The annotation database (default DIR/.interslice/annotations.sqlite).
        #[arg(long)]
        db: Option<PathBuf>,
    },
    /// List the accounts.
    List {
        /// The project folder.
        #[arg(long, default_value = ".")]
        dir: PathBuf,
        /// The annotation database (default DIR/.interslice/annotations.sqlite).
        #[arg(long)]
        db: Option<PathBuf>,
    },
}

fn open(dir: &std::path::Path, db: Option<PathBuf>) -> Result<Store> {
    Ok(interslice_project::open_store(dir, db.as_deref(), None)?)
}

fn read_password() -> Result<String> {
    if let Ok(p) = std::env::var("INTERSLICE_PASSWORD") {
        return Ok(p);
    }
    eprintln!("password (one line on standard input):");
    let mut line = String::new();
    std::io::stdin().lock().read_line(&mut line)?;
    Ok(line.trim_end_matches(['\r', '\n']).to_string())
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    match a.action {
        Action::Add {
            dir,
            name,
            reviewer,
            db,
        } => {
            let store = open(&dir, db)?;
            let password = read_password()?;
            if password.chars().count() < 8 {
                bail!("the password must have at least 8 characters");
            }
            let role = if reviewer {
                Role::Reviewer
            } else {
                Role::Tracer
            };
            let user = store.upsert_user(&name, role, Some(&password))?;
            println!("user '{}' ({})", user.name, role.as_str());
        }
        Action::List { dir, db } => {
            let store = open(&dir, db)?;
            for u in store.users()? {
                println!("{}\t{}", u.name, u.role.as_str());
            }
        }
    }
    Ok(())
}
