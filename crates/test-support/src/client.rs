//! A small blocking HTTP client of the API (ureq, keep-alive), used by the
//! integration tests, the load test and the latency benchmark so that all of
//! them speak to the server exactly as a browser would: over loopback TCP,
//! with the session cookie.
use std::io::Read as _;
use std::time::Duration;

/// A failure to talk to the server at all (an HTTP error status is not one:
/// it is an [`Answer`]).
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// Connection refused or reset, timeout, unreadable answer.
    #[error("transport: {0}")]
    Transport(String),
}

/// An answer of the server, whatever its status.
#[derive(Debug, Clone)]
pub struct Answer {
    /// HTTP status.
    pub status: u16,
    /// `Content-Type`, if any.
    pub content_type: Option<String>,
    /// `X-Width`, `X-Height`, `X-Dtype` of binary slices.
    pub slice_header: Option<(usize, usize, String)>,
    /// `Set-Cookie`, if any.
    pub set_cookie: Option<String>,
    /// The body.
    pub body: Vec<u8>,
}

impl Answer {
    /// The body as JSON (`Null` when it is not JSON).
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).unwrap_or(serde_json::Value::Null)
    }

    /// The `error` message of a JSON error body, if any.
    pub fn error(&self) -> Option<String> {
        self.json()
            .get("error")
            .and_then(|e| e.as_str())
            .map(str::to_string)
    }

    /// Whether the status is 2xx.
    pub fn ok(&self) -> bool {
        (200..300).contains(&self.status)
    }
}

/// One signed-in (or anonymous) client with its own keep-alive connection.
pub struct Client {
    agent: ureq::Agent,
    base: String,
    cookie: Option<String>,
}

impl Client {
    /// A client of `base` (`http://127.0.0.1:PORT`), not signed in.
    pub fn new(base: &str) -> Client {
        let agent = ureq::AgentBuilder::new()
            .timeout_connect(Duration::from_secs(5))
            .timeout(Duration::from_secs(120))
            .max_idle_connections_per_host(2)
            .build();
        Client {
            agent,
            base: base.trim_end_matches('/').to_string(),
            cookie: None,
        }
    }

    /// `POST /api/login`; on success the session cookie is kept for later calls.
    pub fn login(&mut self, name: &str, password: Option<&str>) -> Result<Answer, ClientError> {
        let mut body = serde_json::json!({ "name": name });
        if let Some(p) = password {
            body["password"] = p.into();
        }
        let a = self.json("POST", "/api/login", &body)?;
        if let Some(c) = &a.set_cookie {
            // Keep `name=value`, drop the attributes.
            self.cookie = c.split(';').next().map(str::to_string);
        }
        Ok(a)
    }

    /// Use a given `Cookie` header value (or none).
    pub fn set_cookie(&mut self, cookie: Option<String>) {
        self.cookie = cookie;
    }

    /// The `Cookie` header this client sends.
    pub fn cookie(&self) -> Option<&str> {
        self.cookie.as_deref()
    }

    /// Send any request; `body` is sent as is with `content_type`.
    pub fn send(
        &self,
        method: &str,
        path: &str,
        body: Option<(&[u8], &str)>,
    ) -> Result<Answer, ClientError> {
        let mut req = self.agent.request(method, &format!("{}{path}", self.base));
        if let Some(c) = &self.cookie {
            req = req.set("Cookie", c);
        }
        let res = match body {
            Some((bytes, ct)) => req.set("Content-Type", ct).send_bytes(bytes),
            None => req.call(),
        };
        let resp = match res {
            Ok(r) => r,
            Err(ureq::Error::Status(_, r)) => r,
            Err(e) => return Err(ClientError::Transport(e.to_string())),
        };
        let status = resp.status();
        let content_type = resp.header("content-type").map(str::to_string);
        let set_cookie = resp.header("set-cookie").map(str::to_string);
        let slice_header = match (
            resp.header("x-width").and_then(|v| v.parse().ok()),
            resp.header("x-height").and_then(|v| v.parse().ok()),
            resp.header("x-dtype"),
        ) {
            (Some(w), Some(h), Some(d)) => Some((w, h, d.to_string())),
            _ => None,
        };
        let mut body = Vec::new();
        resp.into_reader()
            .read_to_end(&mut body)
            .map_err(|e| ClientError::Transport(e.to_string()))?;
        Ok(Answer {
            status,
            content_type,
            slice_header,
            set_cookie,
            body,
        })
    }

    /// A request without body.
    pub fn get(&self, path: &str) -> Result<Answer, ClientError> {
        self.send("GET", path, None)
    }

    /// `DELETE path`.
    pub fn delete(&self, path: &str) -> Result<Answer, ClientError> {
        self.send("DELETE", path, None)
    }

    /// A request with a JSON body.
    pub fn json(
        &self,
        method: &str,
        path: &str,
        body: &serde_json::Value,
    ) -> Result<Answer, ClientError> {
        let bytes = serde_json::to_vec(body).map_err(|e| ClientError::Transport(e.to_string()))?;
        self.send(method, path, Some((&bytes, "application/json")))
    }
}

/// The `q`-quantile of sorted samples (linear interpolation between order
/// statistics, numpy's default); `None` when empty.
pub fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    Some(sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64))
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn quantiles_interpolate_like_numpy() {
        let s = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&s, 0.5), Some(2.5));
        assert!((quantile(&s, 0.99).unwrap() - 3.97).abs() < 1e-12);
        assert_eq!(quantile(&s, 0.0), Some(1.0));
        assert_eq!(quantile(&[], 0.5), None);
    }
}
