//! What the studio's socket tests share: a running studio (stopped when dropped), and a client
//! that speaks the page's protocol and keeps what the server told it, as a page does.

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use tungstenite::{Message, WebSocket};

/// A running studio, killed when dropped.
pub struct Studio {
    pub child: Child,
    pub port: u16,
    pub token: String,
    pub url: String,
}

impl Studio {
    /// Stops the studio as Ctrl+C does (it writes its autosave) and waits for it.
    pub fn interrupt(&mut self) {
        let pid = self.child.id().to_string();
        assert!(Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .expect("kill")
            .success());
        let _ = self.child.wait();
    }

    /// `bdmorph studio ARGS...` in `dir`.
    pub fn start_with(dir: &Path, args: &[&str]) -> Studio {
        Studio::start_env(dir, args, &[])
    }

    /// `bdmorph studio ARGS...` in `dir` with the environment variables `env` set.
    pub fn start_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Studio {
        // BDMORPH_BIN runs another build of the program (the release one, for timings).
        // A relative path is taken from where the tests run (the program runs in `dir`).
        let program = std::env::var_os("BDMORPH_BIN").map_or_else(
            || PathBuf::from(env!("CARGO_BIN_EXE_bdmorph")),
            |p| std::path::absolute(PathBuf::from(p)).expect("BDMORPH_BIN: a path"),
        );
        let mut c = Command::new(program);
        c.arg("studio").args(args).current_dir(dir);
        c.envs(env.iter().copied());
        let mut child = c
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("the URL line");
        let url = line.trim().to_owned();
        let rest = url
            .strip_prefix("http://127.0.0.1:")
            .unwrap_or_else(|| panic!("a loopback URL, not {url:?}"));
        let (port, query) = rest.split_once("/?token=").expect("a token");
        Studio {
            child,
            port: port.parse().expect("port"),
            token: query.to_owned(),
            url,
        }
    }

    pub fn start(dir: &Path, file: Option<&str>) -> Studio {
        Studio::start_with(dir, file.as_slice())
    }

    /// Sends raw bytes as one HTTP request; the status code of the answer.
    pub fn raw(&self, request: &[u8]) -> u16 {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).expect("connects");
        s.set_read_timeout(Some(Duration::from_secs(10)))
            .expect("timeout");
        s.write_all(request).expect("writes");
        let mut answer = Vec::new();
        let _ = s.read_to_end(&mut answer);
        let text = String::from_utf8_lossy(&answer);
        text.split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0)
    }

    pub fn get(&self, path: &str, extra_headers: &str) -> u16 {
        let request = format!(
            "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n{extra_headers}Connection: close\r\n\r\n",
            self.port
        );
        self.raw(request.as_bytes())
    }

    pub fn page_is_served(&self) -> bool {
        self.get(&format!("/?token={}", self.token), "") == 200
    }

    pub fn client(&self) -> Client {
        let url = format!("ws://127.0.0.1:{}/ws?token={}", self.port, self.token);
        let (ws, _) = tungstenite::connect(url).expect("socket opens");
        let mut client = Client {
            ws,
            state: serde_json::Value::Null,
            pins: Vec::new(),
            outline: serde_json::Value::Null,
            mesh: Vec::new(),
            frame: Vec::new(),
            errors: Vec::new(),
            files: serde_json::Value::Null,
            exists: None,
            seq: 0,
        };
        client.request(r#"{"op":"hello"}"#);
        client
    }

    /// `GET PATH` with the token; the status code of the answer.
    pub fn get_with_token(&self, path: &str) -> u16 {
        let sep = if path.contains('?') { '&' } else { '?' };
        self.get(&format!("{path}{sep}token={}", self.token), "")
    }

    /// The studio's resident memory in bytes (Linux).
    pub fn resident(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id()))
            .unwrap_or_default();
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map_or(0, |kb| kb * 1024)
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub type Socket = WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>;

/// A page as the server sees it: what it was told last.
pub struct Client {
    pub ws: Socket,
    pub state: serde_json::Value,
    pub pins: Vec<u32>,
    pub outline: serde_json::Value,
    pub mesh: Vec<u8>,
    /// The last frame (pose or animation), binary.
    pub frame: Vec<u8>,
    pub errors: Vec<String>,
    pub files: serde_json::Value,
    /// The last `{"type": "exists"}` answer (an export onto something that is there).
    pub exists: Option<serde_json::Value>,
    pub seq: u32,
}

impl Client {
    /// Reads one message and keeps what it says; `false` when the socket is gone.
    pub fn read_one(&mut self) -> bool {
        match self.ws.read() {
            Ok(Message::Text(t)) => {
                let v: serde_json::Value = serde_json::from_str(t.as_str()).expect("JSON");
                match v["type"].as_str() {
                    Some("state") => self.state = v,
                    Some("pins") => {
                        self.pins = v["pins"]
                            .as_array()
                            .map(|a| {
                                a.iter()
                                    .filter_map(|p| p.as_u64())
                                    .map(|p| p as u32)
                                    .collect()
                            })
                            .unwrap_or_default();
                    }
                    Some("outline") => self.outline = v["loops"].clone(),
                    Some("error") => self
                        .errors
                        .push(v["message"].as_str().unwrap_or("").to_owned()),
                    Some("files") => self.files = v,
                    Some("exists") => self.exists = Some(v),
                    _ => {}
                }
                true
            }
            Ok(Message::Binary(b)) => {
                let kind = u32::from_le_bytes(b[..4].try_into().expect("kind"));
                if kind == 2 {
                    self.mesh = b.to_vec();
                } else {
                    self.frame = b.to_vec();
                }
                true
            }
            Ok(_) => true,
            Err(_) => false,
        }
    }

    /// Sends `json` and reads until the server has carried it out (a `list_files` sent after
    /// it is answered); the error it caused, if any.
    pub fn request(&mut self, json: &str) -> Option<String> {
        let before = self.errors.len();
        self.ws.send(Message::Text(json.into())).expect("sends");
        self.ws
            .send(Message::Text(r#"{"op":"list_files"}"#.into()))
            .expect("sends");
        self.files = serde_json::Value::Null;
        while self.files.is_null() {
            assert!(self.read_one(), "the socket closed");
        }
        self.errors.get(before).cloned()
    }

    /// Reads everything the server has sent so far (a `list_files` sent now is answered
    /// after it).
    pub fn sync(&mut self) {
        self.ws
            .send(Message::Text(r#"{"op":"list_files"}"#.into()))
            .expect("sends");
        self.files = serde_json::Value::Null;
        while self.files.is_null() {
            assert!(self.read_one(), "the socket closed");
        }
    }

    /// Reads what the server sends (its own changes, such as a background job's) until `done`
    /// holds, or panics after `seconds`.
    pub fn wait_for(&mut self, seconds: u64, what: &str, done: impl Fn(&Client) -> bool) {
        let start = Instant::now();
        loop {
            self.sync();
            if done(self) {
                return;
            }
            assert!(
                start.elapsed() < Duration::from_secs(seconds),
                "timed out waiting for {what}; state: {}",
                self.state
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// A drag of the shown keyframe's pins to `targets`; the error, if any.
    pub fn drag(&mut self, targets: &[[f64; 2]]) -> Option<String> {
        self.seq += 1;
        let request = serde_json::json!({"op": "drag", "seq": self.seq, "pins": self.pins, "targets": targets});
        self.request(&request.to_string())
    }

    /// A drag of the shown keyframe's pins to `targets`, moving only the pins `moving` (the
    /// others stay where the keyframe has them, whatever `targets` says); the error, if any.
    pub fn drag_moving(&mut self, targets: &[[f64; 2]], moving: &[u32]) -> Option<String> {
        self.seq += 1;
        let request = serde_json::json!({"op": "drag", "seq": self.seq, "pins": self.pins, "targets": targets, "moving": moving});
        self.request(&request.to_string())
    }

    /// Sends a binary upload of `bytes` as `name`, then what it does (`open`, `attach`,
    /// `store`), and reads until it is carried out; the error it caused, if any.
    pub fn upload(&mut self, name: &str, then: &str, bytes: &[u8]) -> Option<String> {
        let header = serde_json::json!({"name": name, "then": then}).to_string();
        let mut message = Vec::new();
        message.extend_from_slice(&10u32.to_le_bytes());
        message.extend_from_slice(&(header.len() as u32).to_le_bytes());
        message.extend_from_slice(header.as_bytes());
        message.extend_from_slice(bytes);
        let before = self.errors.len();
        self.ws
            .send(Message::Binary(message.into()))
            .expect("sends");
        self.sync();
        self.errors.get(before).cloned()
    }

    /// The positions of the last frame.
    pub fn positions(&self) -> Vec<[f32; 2]> {
        positions(&self.frame)
    }

    /// The last notes' texts.
    pub fn notes(&self) -> Vec<String> {
        self.state["notes"]
            .as_array()
            .map(|a| {
                a.iter()
                    .map(|n| n["text"].as_str().unwrap_or("").to_owned())
                    .collect()
            })
            .unwrap_or_default()
    }
}

/// Positions of a binary frame (kind 1 or 3).
pub fn positions(frame: &[u8]) -> Vec<[f32; 2]> {
    if frame.len() < 40 {
        return Vec::new();
    }
    let n = u32::from_le_bytes(frame[8..12].try_into().expect("n")) as usize;
    (0..n)
        .map(|i| {
            let at = 40 + 8 * i;
            [
                f32::from_le_bytes(frame[at..at + 4].try_into().expect("x")),
                f32::from_le_bytes(frame[at + 4..at + 8].try_into().expect("y")),
            ]
        })
        .collect()
}

pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-studio-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}
