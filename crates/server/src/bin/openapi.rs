//! `openapi > openapi.json`: print the OpenAPI document of the HTTP API (what
//! `GET /api/openapi.json` serves) without starting a server, so clients'
//! types can be generated from it.

fn main() {
    match interslice_server::openapi::document().to_pretty_json() {
        Ok(text) => println!("{text}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
