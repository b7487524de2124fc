//! The `Host` check of a loopback server (DNS rebinding).
//!
//! A page on `attacker.example` whose name is re-pointed at 127.0.0.1 talks
//! to a loopback server as the same origin, and a loopback server signs in
//! by name: without this check it could read and change every tracing. So a
//! loopback server answers only requests whose `Host` is a loopback name
//! (`localhost`, `*.localhost`, `127.0.0.0/8`, `[::1]`) or a host named by
//! `--public-url` (a reverse proxy in front of it). Off loopback, passwords
//! protect the server and any `Host` is answered.
use crate::error::error_response;
use axum::http::StatusCode;
use axum::http::header::HOST;
use std::net::IpAddr;

/// Which `Host` names a server answers.
#[derive(Debug, Clone, Default)]
pub struct HostPolicy {
    /// Check at all (the server listens on loopback).
    pub loopback_only: bool,
    /// Host names allowed besides the loopback ones, lower case, no port.
    pub extra: Vec<String>,
}

/// The host name of a `Host` header value: lower case, without port and
/// brackets, without a trailing dot.
fn host_name(value: &str) -> String {
    let v = value.trim();
    let name = if let Some(rest) = v.strip_prefix('[') {
        rest.split(']').next().unwrap_or("")
    } else {
        match v.rsplit_once(':') {
            Some((h, port)) if port.bytes().all(|b| b.is_ascii_digit()) => h,
            _ => v,
        }
    };
    name.trim_end_matches('.').to_ascii_lowercase()
}

/// Whether `name` (from [`host_name`]) is a loopback name.
fn is_loopback_name(name: &str) -> bool {
    name == "localhost"
        || name.ends_with(".localhost")
        || name.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

impl HostPolicy {
    /// Whether a request with this `Host` header value is answered.
    pub fn allows(&self, host: Option<&str>) -> bool {
        if !self.loopback_only {
            return true;
        }
        let Some(host) = host else {
            return false;
        };
        let name = host_name(host);
        is_loopback_name(&name) || self.extra.contains(&name)
    }
}

/// The host of a `--public-url` (`https://tracing.example.org/`), as a
/// [`HostPolicy::extra`] entry.
pub fn public_url_host(url: &str) -> Result<String, String> {
    let uri: axum::http::Uri = url
        .parse()
        .map_err(|e| format!("--public-url '{url}' is not a URL: {e}"))?;
    let host = uri.host().ok_or_else(|| {
        format!("--public-url '{url}' names no host (e.g. https://tracing.example.org)")
    })?;
    Ok(host_name(host))
}

/// Middleware: 403 with a JSON error for a `Host` the policy refuses.
pub async fn check(
    policy: std::sync::Arc<HostPolicy>,
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> axum::response::Response {
    let host = req.headers().get(HOST).and_then(|v| v.to_str().ok());
    if policy.allows(host) {
        return next.run(req).await;
    }
    error_response(
        StatusCode::FORBIDDEN,
        "this server listens on loopback and answers only localhost names \
         (start it with --public-url to serve it through a proxy)",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_servers_answer_loopback_names_and_public_urls() {
        let p = HostPolicy {
            loopback_only: true,
            extra: vec![public_url_host("https://Tracing.Example.org/app").unwrap()],
        };
        for ok in [
            "localhost",
            "localhost:8080",
            "LOCALHOST.",
            "app.localhost:1",
            "127.0.0.1:8080",
            "127.1.2.3",
            "[::1]:8080",
            "tracing.example.org",
            "tracing.example.org:443",
        ] {
            assert!(p.allows(Some(ok)), "{ok}");
        }
        for bad in [
            "attacker.example",
            "attacker.example:8080",
            "localhost.attacker.example",
            "127.0.0.1.attacker.example",
            "10.0.0.1",
            "[::2]",
            "",
        ] {
            assert!(!p.allows(Some(bad)), "{bad}");
        }
        assert!(!p.allows(None));
        assert!(HostPolicy::default().allows(Some("attacker.example")));
        assert!(public_url_host("/relative").is_err());
    }
}
