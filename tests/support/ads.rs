//! Shared helpers for the ADS integration tests: a server over real channels (a `Machine`
//! ticking in real time at 1 ms on its own thread, as `ncchannel serve` runs it) and a raw
//! frame-level client, so tests can check bytes on the wire.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ncchannel::ads::backend::{CncBackend, Op, Status};
use ncchannel::ads::frame::{self, AmsAddr, AmsHeader, CommandId, Frame};
use ncchannel::ads::{spawn, ServerConfig, ServerHandle};
use ncchannel::machine::remote::Ticking;
use ncchannel::machine::{Machine, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::vocab::ams::AmsNetId;
use serde_json::Value;

pub const CH1: u32 = 0x20101;

/// The event log's bytes, shared with the log writer thread.
#[derive(Clone, Default)]
struct LogBytes(Arc<Mutex<Vec<u8>>>);

impl Write for LogBytes {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Parameter lists of `n` channels and their programs in a temporary folder: each channel has
/// the streaming program `streaming.nc`, the default axes X Y Z, and programs in `nc/`.
/// Tests may add programs and change the lists before the channels start.
pub struct Params {
    pub dir: tempfile::TempDir,
}

impl Params {
    pub fn new(n: u16) -> Params {
        let dir = tempfile::tempdir().unwrap();
        let params = dir.path().join("params");
        std::fs::create_dir_all(&params).unwrap();
        std::fs::create_dir_all(dir.path().join("nc")).unwrap();
        let mut startup = format!("kanal_anzahl {n}\n");
        for i in 0..n {
            startup.push_str(&format!(
                "sda_mds[{i}] channel{ch}.lis\npfad[{i}].prg[0] ../nc\npfad[{i}].typ[0] 0x03\n\
                 pfad[{i}].prioritaet[0] 0\n",
                ch = i + 1
            ));
            std::fs::write(
                params.join(format!("channel{}.lis", i + 1)),
                "streaming_prog_file streaming.nc\n",
            )
            .unwrap();
        }
        std::fs::write(params.join("startup.lis"), startup).unwrap();
        Params { dir }
    }

    /// The start-up list (`params/startup.lis`).
    pub fn startup(&self) -> PathBuf {
        self.dir.path().join("params/startup.lis")
    }

    /// Write program `name` into `nc/`.
    pub fn program(&self, name: &str, text: &str) -> PathBuf {
        let p = self.dir.path().join("nc").join(name);
        std::fs::write(&p, text).unwrap();
        p
    }
}

/// Real channels running behind a backend: a `Machine` from [`Params`], ticking in real time
/// (1 ms, the lists' default) on its own thread; they start in AUTOMATIC / READY, as the
/// controller does.
pub struct Channels {
    pub backend: Arc<dyn CncBackend>,
    ticking: Option<Ticking>,
    log: LogBytes,
    pub params: Params,
}

impl Channels {
    /// `n` channels with the lists of [`Params::new`].
    pub fn start(n: u16) -> Channels {
        Channels::from_params(Params::new(n))
    }

    pub fn from_params(params: Params) -> Channels {
        let config = ncchannel::params::load(&params.startup()).unwrap();
        let channels = ncchannel::channels(&config, true, &ncchannel::Loader::start()).unwrap();
        let log = LogBytes::default();
        let mut machine = Machine::new(
            channels,
            EventLog::to_writer(Box::new(log.clone())),
            StopWhen::Never,
        );
        // As `serve --http` does: the web view's tests open pages after programs started.
        machine.record_live();
        let period = Duration::from_micros(config.runtime.cycle_period_us);
        let (backend, ticking) = Ticking::start(machine, period).unwrap();
        Channels {
            backend: Arc::new(backend),
            ticking: Some(ticking),
            log,
            params,
        }
    }

    /// Channel `ch`'s status, asked through the backend as the objects ask.
    pub fn status(&self, ch: u16) -> Status {
        self.backend.status(ch).unwrap()
    }

    /// Apply `op` to channel `ch` directly (test set-up, not the object under test).
    pub fn command(&self, ch: u16, op: Op) {
        self.backend.command(ch, op).unwrap();
    }

    /// Wait (bounded) until channel `ch`'s status satisfies `done`; the last status.
    pub fn wait_for(&self, ch: u16, within: Duration, done: impl Fn(&Status) -> bool) -> Status {
        let deadline = Instant::now() + within;
        loop {
            let s = self.status(ch);
            if done(&s) {
                return s;
            }
            assert!(
                Instant::now() < deadline,
                "not reached within {within:?}: {s:?}"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Stop the runtime and return the machine's event log as JSON values.
    pub fn events(mut self) -> Vec<Value> {
        let mut m: Machine = self.ticking.take().unwrap().stop().unwrap();
        m.finish_log().unwrap();
        let text = String::from_utf8(self.log.0.lock().unwrap().clone()).unwrap();
        text.lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }
}

/// Events of one kind (`ev`), in order.
pub fn of<'a>(events: &'a [Value], ev: &str) -> Vec<&'a Value> {
    events.iter().filter(|e| e["ev"] == ev).collect()
}

/// How many warnings with ISG number `code` the channels raised.
pub fn warnings(events: &[Value], code: u64) -> usize {
    of(events, "warning")
        .iter()
        .filter(|e| e["code"] == code)
        .count()
}

/// Stream writes the channel refused with `code`: a stretch of refusals logs its first as a
/// `warning` and closes with one `writes_refused` event counting them all.
pub fn refusals(events: &[Value], code: u64) -> u64 {
    of(events, "writes_refused")
        .iter()
        .filter(|e| e["code"] == code)
        .map(|e| e["count"].as_u64().unwrap_or(0))
        .sum()
}

/// Texts of the `block` events, in order: the lines the channel executed.
pub fn block_texts(events: &[Value]) -> Vec<String> {
    of(events, "block")
        .iter()
        .map(|e| e["text"].as_str().unwrap().to_string())
        .collect()
}

/// A server on a loopback port over two real channels, with `config` otherwise.
pub fn server_with(config: ServerConfig) -> (ServerHandle, Channels) {
    serve(Channels::start(2), config)
}

/// A server on a loopback port over `channels`, with `config` otherwise.
pub fn serve(channels: Channels, config: ServerConfig) -> (ServerHandle, Channels) {
    let config = ServerConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        ..config
    };
    let handle = spawn(config, Arc::clone(&channels.backend)).expect("server starts");
    (handle, channels)
}

/// The channels of `params` behind a server on a loopback port, as `ncchannel serve` runs them.
pub struct Served {
    pub server: ServerHandle,
    pub channels: Channels,
}

impl Served {
    pub fn start(params: Params) -> Served {
        let (server, channels) = serve(Channels::from_params(params), ServerConfig::default());
        Served { server, channels }
    }

    /// Shut the server down, stop the channels and return their event log.
    pub fn finish(self) -> Vec<Value> {
        self.server.shutdown();
        self.channels.events()
    }
}

pub fn server() -> (ServerHandle, Channels) {
    server_with(ServerConfig::default())
}

pub fn device() -> AmsAddr {
    AmsAddr {
        net_id: "5.6.7.8.1.1".parse().unwrap(),
        port: 553,
    }
}

pub fn client_addr(port: u16) -> AmsAddr {
    AmsAddr {
        net_id: "10.1.2.3.1.1".parse().unwrap(),
        port,
    }
}

pub fn request_bytes(
    command: u16,
    target: AmsAddr,
    source: AmsAddr,
    invoke: u32,
    data: &[u8],
) -> Vec<u8> {
    frame::encode(
        &AmsHeader {
            target,
            source,
            command: CommandId::from_u16(command),
            state_flags: 0x0004,
            error: 0,
            invoke_id: invoke,
        },
        data,
    )
}

/// A raw connection that reads whole frames, keeping the leftover bytes.
pub struct Raw {
    pub stream: TcpStream,
    buf: Vec<u8>,
}

impl Raw {
    pub fn connect(addr: SocketAddr) -> Raw {
        let stream = TcpStream::connect(addr).unwrap();
        stream.set_nodelay(true).unwrap();
        Raw {
            stream,
            buf: Vec::new(),
        }
    }

    pub fn send(&mut self, bytes: &[u8]) {
        self.stream.write_all(bytes).unwrap();
    }

    /// The next frame's raw bytes, or None on timeout / close.
    pub fn frame_bytes(&mut self, timeout: Duration) -> Option<Vec<u8>> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Ok(Some((_, n))) = frame::decode(&self.buf, 1 << 20) {
                return Some(self.buf.drain(..n).collect());
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            if left.is_zero() {
                return None;
            }
            self.stream.set_read_timeout(Some(left)).unwrap();
            let mut chunk = [0u8; 4096];
            match self.stream.read(&mut chunk) {
                Ok(0) => return None,
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(_) => return None,
            }
        }
    }

    /// The next frame, decoded.
    pub fn frame(&mut self) -> (AmsHeader, Vec<u8>) {
        let bytes = self
            .frame_bytes(Duration::from_secs(5))
            .expect("a frame within 5 s");
        match frame::decode(&bytes, 1 << 20).unwrap().unwrap().0 {
            Frame::Ams { header, data } => (header, data),
            other => panic!("unexpected {other:?}"),
        }
    }

    /// True when the server closed the connection (EOF or reset) within `timeout`.
    pub fn closed_within(&mut self, timeout: Duration) -> bool {
        closed_within(&mut self.stream, timeout)
    }

    /// Send one request from `client_addr(port)` to `device()` and return the response.
    pub fn call(&mut self, command: u16, invoke: u32, data: &[u8]) -> (AmsHeader, Vec<u8>) {
        self.send(&request_bytes(
            command,
            device(),
            client_addr(40000),
            invoke,
            data,
        ));
        self.frame()
    }
}

/// True when the peer closed `stream` (EOF or reset) within `timeout`; whatever it still
/// sends meanwhile is read and dropped.
pub fn closed_within(stream: &mut TcpStream, timeout: Duration) -> bool {
    let deadline = Instant::now() + timeout;
    let mut chunk = [0u8; 8192];
    loop {
        let Some(left) = deadline.checked_duration_since(Instant::now()) else {
            return false;
        };
        let _ = stream.set_read_timeout(Some(left.max(Duration::from_millis(1))));
        match stream.read(&mut chunk) {
            Ok(0) => return true,
            Ok(_) => continue,
            Err(e) => {
                if !matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) {
                    return true;
                }
            }
        }
    }
}

pub fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

pub fn read_req(group: u32, offset: u32, length: u32) -> Vec<u8> {
    ncchannel::ads::payload::request::read(group, offset, length)
}

pub fn write_req(group: u32, offset: u32, data: &[u8]) -> Vec<u8> {
    ncchannel::ads::payload::request::write(group, offset, data)
}

pub fn local_net_id() -> AmsNetId {
    AmsNetId::LOCAL
}
