//! Embeds the web UI: every file under `web/dist` becomes a static byte slice
//! in `$OUT_DIR/assets.rs`. When `web/dist` does not exist yet (a fresh clone
//! that has not run `npm run build`), a placeholder page telling the user to
//! run `scripts/demo.sh` is embedded instead, so the build never fails.
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, base: &Path, out: &mut Vec<(String, PathBuf)>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().collect();
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let p = e.path();
        if p.is_dir() {
            collect(&p, base, out);
        } else if let Ok(rel) = p.strip_prefix(base) {
            let rel = rel.to_string_lossy().replace('\\', "/");
            out.push((rel, p));
        }
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let web = manifest.join("../../web");
    let dist = web.join("dist");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    let mut files = Vec::new();
    if dist.join("index.html").is_file() {
        println!("cargo:rerun-if-changed={}", dist.display());
        collect(&dist, &dist, &mut files);
    } else {
        // Rebuild when the UI gets built (web/ changes) or appears.
        if web.is_dir() {
            println!("cargo:rerun-if-changed={}", web.display());
        }
        let placeholder = out_dir.join("placeholder-index.html");
        std::fs::write(
            &placeholder,
            "<!doctype html><html><head><meta charset=\"utf-8\"><title>interslice</title></head>\
             <body><h1>interslice</h1><p>The web UI has not been built into this binary. \
             Run <code>./scripts/demo.sh</code> (it builds <code>web/</code> with \
             <code>npm ci &amp;&amp; npm run build</code> and then the server), or use the \
             HTTP API described at <a href=\"/api/openapi.json\">/api/openapi.json</a>.</p>\
             </body></html>\n",
        )
        .expect("write placeholder");
        files.push(("index.html".to_string(), placeholder));
    }
    let mut src = String::from("/// Embedded web UI files: (path relative to web/dist, bytes).\n");
    src.push_str("pub static ASSETS: &[(&str, &[u8])] = &[\n");
    for (rel, path) in &files {
        let abs = path.canonicalize().unwrap_or_else(|_| path.clone());
        writeln!(
            src,
            "    ({rel:?}, include_bytes!({:?})),",
            abs.display().to_string()
        )
        .expect("write to String");
    }
    src.push_str("];\n");
    std::fs::write(out_dir.join("assets.rs"), src).expect("write assets.rs");
    println!("cargo:rerun-if-changed=build.rs");
}
