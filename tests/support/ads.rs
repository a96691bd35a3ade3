//! Shared helpers for the ADS integration tests: a server over the in-memory backend and a
//! raw frame-level client, so tests can check bytes on the wire.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ncchannel::ads::frame::{self, AmsAddr, AmsHeader, CommandId, Frame};
use ncchannel::ads::memory::{DrainRate, MemoryBackend};
use ncchannel::ads::{spawn, ServerConfig, ServerHandle};
use ncchannel::vocab::ams::AmsNetId;

pub const CH1: u32 = 0x20101;

pub fn server_with(config: ServerConfig, rate: DrainRate) -> (ServerHandle, Arc<MemoryBackend>) {
    let backend = MemoryBackend::new(2, rate);
    let config = ServerConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        ..config
    };
    let handle = spawn(config, backend.clone()).expect("server starts");
    (handle, backend)
}

pub fn server() -> (ServerHandle, Arc<MemoryBackend>) {
    server_with(ServerConfig::default(), DrainRate::default())
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
