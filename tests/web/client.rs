//! A minimal HTTP client over a raw socket for the tests: one request per connection (the
//! server closes each), and a reader of a Server-Sent Events stream.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Status, headers (lower-case names) and body of one response.
pub struct Response {
    pub status: u16,
    pub headers: Vec<(String, String)>,
    pub body: String,
}

impl Response {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

fn connect(addr: SocketAddr) -> TcpStream {
    let s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s
}

/// One request; `extra` are whole header lines.
pub fn request(addr: SocketAddr, method: &str, path: &str, extra: &[&str], body: &str) -> Response {
    let mut head = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nContent-Length: {}\r\n",
        body.len()
    );
    for h in extra {
        head.push_str(h);
        head.push_str("\r\n");
    }
    raw(addr, &format!("{head}\r\n{body}"))
}

/// Send `request` as it is (head and body) and read the whole response.
pub fn raw(addr: SocketAddr, request: &str) -> Response {
    let mut s = connect(addr);
    s.write_all(request.as_bytes()).unwrap();
    let mut raw = String::new();
    s.read_to_string(&mut raw).unwrap();
    let (head, body) = raw.split_once("\r\n\r\n").unwrap();
    let mut lines = head.lines();
    let status = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let headers = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(n, v)| (n.trim().to_ascii_lowercase(), v.trim().to_string()))
        .collect();
    Response {
        status,
        headers,
        body: body.to_string(),
    }
}

pub fn get(addr: SocketAddr, path: &str) -> Response {
    request(addr, "GET", path, &[], "")
}

/// A control request as the page sends it (with its header).
pub fn control(addr: SocketAddr, ch: u16, action: &str, body: &str) -> Response {
    request(
        addr,
        "POST",
        &format!("/control/{ch}/{action}"),
        &["X-Ncchannel-Control: 1"],
        body,
    )
}

/// An open event stream.
pub struct Events {
    pub status: u16,
    reader: BufReader<TcpStream>,
}

impl Events {
    pub fn open(addr: SocketAddr) -> Events {
        let mut s = connect(addr);
        write!(s, "GET /events HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
        let mut reader = BufReader::new(s);
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        let status = line.split(' ').nth(1).map_or(0, |c| c.parse().unwrap_or(0));
        // The rest of the head.
        loop {
            line.clear();
            if reader.read_line(&mut line).unwrap() == 0 || line == "\r\n" {
                break;
            }
        }
        Events { status, reader }
    }

    /// The next event (name and JSON data); `None` when the stream ended.
    pub fn next(&mut self) -> Option<(String, Value)> {
        let (mut name, mut data) = (String::new(), String::new());
        let mut line = String::new();
        loop {
            line.clear();
            if self.reader.read_line(&mut line).ok()? == 0 {
                return None;
            }
            let l = line.trim_end_matches(['\r', '\n']);
            if l.is_empty() {
                if !data.is_empty() {
                    return Some((name, serde_json::from_str(&data).unwrap()));
                }
                continue;
            }
            if let Some(v) = l.strip_prefix("event: ") {
                name = v.to_string();
            } else if let Some(v) = l.strip_prefix("data: ") {
                data.push_str(v);
            }
        }
    }

    /// Read events until `pick` returns a value (within `within`), which is returned.
    pub fn until<T>(
        &mut self,
        within: Duration,
        mut pick: impl FnMut(&str, &Value) -> Option<T>,
    ) -> T {
        let deadline = Instant::now() + within;
        loop {
            assert!(Instant::now() < deadline, "not seen within {within:?}");
            let (name, data) = self.next().expect("the stream goes on");
            if let Some(t) = pick(&name, &data) {
                return t;
            }
        }
    }
}

/// Channel `ch` in a `status` event.
pub fn channel(data: &Value, ch: u64) -> Option<&Value> {
    data["channels"].as_array()?.iter().find(|c| c["ch"] == ch)
}

/// Axis `axis`'s programmed position in a channel of a `status` event.
pub fn axis(c: &Value, axis: &str) -> f64 {
    c["axes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["axis"] == axis)
        .unwrap()["pcs_mm"]
        .as_f64()
        .unwrap()
}
