//! `interslice serve DIR [--bind ADDR] [--db FILE] [--require-login]`: the
//! tracing server and its web UI over a project folder.
use anyhow::Result;
use std::net::SocketAddr;

/// Arguments of `serve`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub project: crate::project::ProjectArgs,
    /// Address to listen on. Off loopback, accounts with passwords are required.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub bind: SocketAddr,
    /// Require accounts with passwords even on loopback.
    #[arg(long)]
    pub require_login: bool,
    /// Largest request body accepted, in MiB (larger requests get 413).
    #[arg(long, default_value_t = 16)]
    pub body_limit_mib: usize,
    /// The URL a reverse proxy serves this server under (repeatable). On
    /// loopback only localhost names are answered, and the hosts of these URLs.
    #[arg(long = "public-url", value_name = "URL")]
    pub public_urls: Vec<String>,
    /// The components traced in this project, comma-separated ("Tumour,Oedema"),
    /// valued 1, 2, … in order; kept in DIR/interslice.toml. Default: the
    /// project file's, else Cell, Nucleus, Nucleolus 1, Nucleolus 2.
    #[arg(long, value_parser = parse_components)]
    pub components: Option<interslice_core::components::Components>,
}

fn parse_components(s: &str) -> Result<interslice_core::components::Components, String> {
    interslice_core::components::Components::from_names(s).map_err(|e| e.to_string())
}

impl Args {
    /// The server configuration these arguments describe.
    pub fn config(&self) -> interslice_server::Config {
        let mut c = interslice_server::Config::new(&self.project.dir);
        c.bind = self.bind;
        c.db = self.project.db.clone();
        c.require_login = self.require_login;
        c.body_limit = self.body_limit_mib << 20;
        c.components = self.components.clone();
        c.public_urls = self.public_urls.clone();
        c
    }
}

/// Run the command: serve until Ctrl-C or SIGTERM.
pub fn run(a: Args) -> Result<()> {
    serve(a.config())
}

/// Serve `config`, printing the URL once listening.
pub fn serve(config: interslice_server::Config) -> Result<()> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    let served = rt.block_on(interslice_server::run(config, |addr, state| {
        let cells = state.cells.read().map(|c| c.len()).unwrap_or(0);
        let login = if state.auth_required {
            "accounts with passwords required (interslice user add)"
        } else {
            "sign in with a name"
        };
        println!("interslice: {cells} cell(s) in {}", state.dir.display());
        println!("interslice: serving on http://{addr}/  ({login}; Ctrl-C stops)");
    }));
    // A computation that has not reached its next cancellation check yet
    // must not hold the process: its answer has nobody to go to.
    rt.shutdown_timeout(std::time::Duration::from_millis(500));
    served
}
