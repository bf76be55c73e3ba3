//! Who may talk to the studio: requests from this machine's loopback, for this server's own
//! address, from its own page, carrying this run's token.
//!
//! - The token (128 random bits, hex) is printed in the URL; every HTTP request and the
//!   WebSocket carry it as `?token=`. Compared in constant time. It is kept in the workspace,
//!   owner-only ([`super::workspace`]), so that a page reconnects to a restarted studio.
//! - `Host` must name the server's own address (`127.0.0.1:P` or `localhost:P`): a page on
//!   another site whose name was rebound to 127.0.0.1 (DNS rebinding) sends its own name.
//! - `Origin`, when present (browsers send it on WebSocket handshakes and non-GET requests),
//!   must be the server's own origin: another site's page cannot open the socket.

/// The per-run secret.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Token(String);

impl Token {
    /// A new random token from the operating system's source.
    pub fn random() -> Result<Token, getrandom::Error> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes)?;
        Ok(Token(bytes.iter().map(|b| format!("{b:02x}")).collect()))
    }

    /// A token from its text: 32 lowercase hexadecimal digits, or `None`.
    pub fn from_hex(text: &str) -> Option<Token> {
        (text.len() == 32 && text.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f')))
            .then(|| Token(text.to_owned()))
    }

    /// The token's text.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `given` is this token, in time independent of where they differ.
    pub fn matches(&self, given: &str) -> bool {
        let (a, b) = (self.0.as_bytes(), given.as_bytes());
        if a.len() != b.len() {
            return false;
        }
        a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
    }
}

/// Whether a `Host` header names this server (loopback by number or by name, on `port`).
pub fn host_is_ours(host: &str, port: u16) -> bool {
    let host = host.trim();
    [format!("127.0.0.1:{port}"), format!("localhost:{port}")]
        .iter()
        .any(|ours| host.eq_ignore_ascii_case(ours))
}

/// Whether an `Origin` header is this server's own page.
pub fn origin_is_ours(origin: &str, port: u16) -> bool {
    let origin = origin.trim();
    [
        format!("http://127.0.0.1:{port}"),
        format!("http://localhost:{port}"),
    ]
    .iter()
    .any(|ours| origin.eq_ignore_ascii_case(ours))
}

/// The `token` parameter of a query string, if any.
pub fn token_in_query(query: &str) -> Option<&str> {
    query
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .find(|(k, _)| *k == "token")
        .map(|(_, v)| v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_random_and_compared_whole() {
        let a = Token::random().expect("random");
        let b = Token::random().expect("random");
        assert_ne!(a, b);
        assert_eq!(a.as_str().len(), 32);
        assert!(a.matches(a.as_str()));
        assert!(!a.matches(b.as_str()));
        assert!(!a.matches(&a.as_str()[..31]));
        assert!(!a.matches(""));
        assert_eq!(Token::from_hex(a.as_str()), Some(a.clone()));
        assert_eq!(Token::from_hex("abc"), None);
        assert_eq!(Token::from_hex(&"G".repeat(32)), None);
    }

    #[test]
    fn only_our_own_host_and_origin_pass() {
        assert!(host_is_ours("127.0.0.1:8080", 8080));
        assert!(host_is_ours("localhost:8080", 8080));
        assert!(!host_is_ours("127.0.0.1:8081", 8080));
        assert!(!host_is_ours("evil.example:8080", 8080));
        assert!(!host_is_ours("127.0.0.1", 8080));
        assert!(origin_is_ours("http://127.0.0.1:8080", 8080));
        assert!(!origin_is_ours("http://evil.example", 8080));
        assert!(!origin_is_ours("https://127.0.0.1:8080", 8080));
        assert!(!origin_is_ours("null", 8080));
        assert_eq!(token_in_query("a=1&token=abc"), Some("abc"));
        assert_eq!(token_in_query("tokens=abc"), None);
    }
}
