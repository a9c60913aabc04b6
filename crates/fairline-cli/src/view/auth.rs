//! The access token and the checks every request passes (see the module
//! documentation of `view` for the rules).

use anyhow::Result;

/// A random token: 32 bytes from the operating system's generator, as hex.
pub fn new_token() -> Result<String> {
    let mut bytes = [0u8; 32];
    getrandom::fill(&mut bytes).map_err(|e| anyhow::anyhow!("no random numbers: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// The token and the port the page is served on.
pub struct Guard {
    token: String,
    port: u16,
}

/// Why a request is refused (the body of the 403 answer).
pub type Refusal = &'static str;

impl Guard {
    pub fn new(token: String, port: u16) -> Self {
        Guard { token, port }
    }

    /// The name of the cookie carrying the token for this port.
    pub fn cookie_name(&self) -> String {
        format!("fairline_{}", self.port)
    }

    /// `Set-Cookie` value given with the page.
    pub fn set_cookie(&self) -> String {
        format!(
            "{}={}; Path=/; HttpOnly; SameSite=Strict",
            self.cookie_name(),
            self.token
        )
    }

    fn same(&self, given: &str) -> bool {
        // constant time in the token's length
        let a = given.as_bytes();
        let b = self.token.as_bytes();
        if a.len() != b.len() {
            return false;
        }
        a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
    }

    /// Checks host, origin, fetch site and token of a request.
    pub fn check(&self, req: &super::http::HttpRequest) -> Result<(), Refusal> {
        let header = |name: &str| -> Option<String> { req.header(name).map(str::to_string) };
        let hosts = [
            format!("127.0.0.1:{}", self.port),
            format!("localhost:{}", self.port),
        ];
        match header("Host") {
            Some(h) if hosts.iter().any(|x| x.eq_ignore_ascii_case(h.trim())) => {}
            _ => return Err("forbidden: wrong Host header"),
        }
        if let Some(o) = header("Origin") {
            let ok = hosts
                .iter()
                .any(|x| o.trim().eq_ignore_ascii_case(&format!("http://{x}")));
            if !ok {
                return Err("forbidden: cross-origin request");
            }
        }
        if header("Sec-Fetch-Site").is_some_and(|s| s.trim().eq_ignore_ascii_case("cross-site")) {
            return Err("forbidden: cross-site request");
        }
        if header("X-Fairline-Token").is_some_and(|t| self.same(t.trim())) {
            return Ok(());
        }
        // the page URL carries the token; API calls that change something
        // (POST) must send the header
        if req.method == "GET" && query_param(&req.url, "token").is_some_and(|t| self.same(&t)) {
            return Ok(());
        }
        if req.method == "GET"
            && let Some(c) = header("Cookie")
        {
            let name = self.cookie_name();
            for part in c.split(';') {
                if let Some((k, v)) = part.trim().split_once('=')
                    && k == name
                    && self.same(v)
                {
                    return Ok(());
                }
            }
        }
        Err("forbidden: missing or wrong token (open the URL fairline view printed)")
    }
}

/// The value of query parameter `name` in `url` (no percent-decoding: the
/// values the page uses are plain).
pub fn query_param(url: &str, name: &str) -> Option<String> {
    let (_, q) = url.split_once('?')?;
    q.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=')?;
        (k == name).then(|| v.to_string())
    })
}
