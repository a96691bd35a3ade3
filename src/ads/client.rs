//! A synchronous ADS/TCP client and the stream feeder behind `ncchannel stream`.
//!
//! The feeder does what the driver in the streaming documentation (ISG FCT-C19 Data streaming §5) does, better:
//! whole lines, LF normalised to CR LF, packets of up to 992 bytes of whole lines instead of
//! one line per write, and a rejected write (0x708, buffer full) retried after about 1 ms
//! instead of a fixed 500 ms sleep, so the buffer never runs dry while the client sleeps.

use std::io::{self, Read, Write};
use std::net::{IpAddr, SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use super::frame::{self, AmsAddr, AmsHeader, CommandId, Frame, FLAGS_REQUEST};
use super::objects::{offset, GROUP_CHANNEL, PORT_CNC_COM};
use super::payload::{self, request};
use super::result::AdsResult;
use crate::vocab::ams::{AmsNetId, DEFAULT_MAX_FRAME_BYTES};

use crate::source::stream::MAX_PROGRAM_STREAM_INPUT_SIZE;
use crate::vocab::mode::{Mode, State};

/// What went wrong talking to the device.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error("I/O: {0}")]
    Io(#[from] io::Error),
    #[error("malformed frame from the device: {0}")]
    Frame(#[from] frame::FrameError),
    #[error("malformed response payload: {0}")]
    Payload(#[from] payload::PayloadError),
    #[error("device answered {0}")]
    Ads(AdsResult),
    #[error("AMS router error {0}")]
    Ams(AdsResult),
    #[error("no response within {0:?}")]
    Timeout(Duration),
    #[error("connection closed by the device")]
    Closed,
}

impl ClientError {
    /// The ADS result in the response's result field, if that is what failed.
    pub fn ads_result(&self) -> Option<AdsResult> {
        match self {
            ClientError::Ads(r) => Some(*r),
            _ => None,
        }
    }
}

/// Name and version the device reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceInfo {
    pub(crate) major: u8,
    pub(crate) minor: u8,
    pub build: u16,
    pub name: String,
}

/// One TCP connection to an ADS device, one request at a time.
pub struct AdsClient {
    stream: TcpStream,
    target: AmsAddr,
    source: AmsAddr,
    invoke_id: u32,
    buf: Vec<u8>,
    timeout: Duration,
}

impl AdsClient {
    /// Connect to `addr` and address requests to `target`. `source` defaults to the local
    /// IPv4 address + `.1.1`, AMS port 32905.
    pub fn connect(
        addr: SocketAddr,
        target: AmsAddr,
        source: Option<AmsAddr>,
        timeout: Duration,
    ) -> Result<Self, ClientError> {
        let stream = TcpStream::connect_timeout(&addr, timeout)?;
        stream.set_nodelay(true)?;
        stream.set_write_timeout(Some(timeout))?;
        let source = match source {
            Some(s) => s,
            None => {
                let octets = match stream.local_addr()?.ip() {
                    IpAddr::V4(v4) => v4.octets(),
                    IpAddr::V6(_) => [127, 0, 0, 1],
                };
                let [a, b, c, d] = octets;
                AmsAddr {
                    net_id: AmsNetId([a, b, c, d, 1, 1]),
                    port: 32905,
                }
            }
        };
        Ok(AdsClient {
            stream,
            target,
            source,
            invoke_id: 0,
            buf: Vec::with_capacity(4096),
            timeout,
        })
    }

    pub fn source(&self) -> AmsAddr {
        self.source
    }

    /// Send one request and wait for its response payload (header error checked, result
    /// not). Notifications and stray frames arriving meanwhile are skipped.
    pub fn request(&mut self, command: CommandId, data: &[u8]) -> Result<Vec<u8>, ClientError> {
        self.invoke_id = self.invoke_id.wrapping_add(1);
        let header = AmsHeader {
            target: self.target,
            source: self.source,
            command,
            state_flags: FLAGS_REQUEST,
            error: 0,
            invoke_id: self.invoke_id,
        };
        self.stream.write_all(&frame::encode(&header, data))?;
        let deadline = Instant::now() + self.timeout;
        loop {
            if let Some((f, n)) = frame::decode(&self.buf, DEFAULT_MAX_FRAME_BYTES)? {
                self.buf.drain(..n);
                if let Frame::Ams { header: h, data } = f {
                    if h.command == command
                        && h.invoke_id == self.invoke_id
                        && h.state_flags & 1 == 1
                    {
                        if h.error != 0 {
                            return Err(ClientError::Ams(AdsResult(h.error)));
                        }
                        return Ok(data);
                    }
                }
                continue;
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(ClientError::Timeout(self.timeout));
            }
            self.stream.set_read_timeout(Some(left))?;
            let mut chunk = [0u8; 4096];
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(ClientError::Closed),
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                    ) =>
                {
                    return Err(ClientError::Timeout(self.timeout))
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
    }

    fn checked(result: AdsResult) -> Result<(), ClientError> {
        if result.is_ok() {
            Ok(())
        } else {
            Err(ClientError::Ads(result))
        }
    }

    pub fn read_device_info(&mut self) -> Result<DeviceInfo, ClientError> {
        let data = self.request(CommandId::ReadDeviceInfo, &[])?;
        Self::checked(payload::decode_result(&data)?)?;
        if data.len() < 24 {
            return Err(payload::PayloadError::Short {
                need: 24,
                got: data.len(),
            }
            .into());
        }
        let name_bytes = &data[8..24];
        let end = name_bytes.iter().position(|&b| b == 0).unwrap_or(16);
        Ok(DeviceInfo {
            major: data[4],
            minor: data[5],
            build: u16::from_le_bytes([data[6], data[7]]),
            name: String::from_utf8_lossy(&name_bytes[..end]).into_owned(),
        })
    }

    /// ADS Read of up to `length` bytes.
    pub fn read(&mut self, group: u32, off: u32, length: u32) -> Result<Vec<u8>, ClientError> {
        let data = self.request(CommandId::Read, &request::read(group, off, length))?;
        let (result, bytes) = payload::decode_data_response(&data)?;
        Self::checked(result)?;
        Ok(bytes)
    }

    /// ADS Write.
    pub fn write(&mut self, group: u32, off: u32, bytes: &[u8]) -> Result<(), ClientError> {
        let data = self.request(CommandId::Write, &request::write(group, off, bytes))?;
        Self::checked(payload::decode_result(&data)?)
    }

    /// ADS ReadWrite.
    pub fn read_write(
        &mut self,
        group: u32,
        off: u32,
        read_length: u32,
        bytes: &[u8],
    ) -> Result<Vec<u8>, ClientError> {
        let req = request::read_write(group, off, read_length, bytes);
        let data = self.request(CommandId::ReadWrite, &req)?;
        let (result, out) = payload::decode_data_response(&data)?;
        Self::checked(result)?;
        Ok(out)
    }

    /// ADS ReadState: (ADS state, device state).
    pub fn read_state(&mut self) -> Result<(u16, u16), ClientError> {
        let data = self.request(CommandId::ReadState, &[])?;
        Self::checked(payload::decode_result(&data)?)?;
        let mut c = payload::Cursor::new(&data[4..]);
        Ok((c.u16()?, c.u16()?))
    }
}

pub use crate::source::packets::{packets, LineTooLong};

/// Settings of one streaming run.
#[derive(Debug, Clone)]
pub struct StreamOptions {
    /// 1-based channel number (index group 0x20100 + channel).
    pub channel: u16,
    /// Packet size limit, 1..=992.
    pub packet_bytes: usize,
    /// Pause before retrying a write rejected with 0x708.
    pub retry: Duration,
    /// `Some(name)`: select AUTOMATIC, pass `name`, command ACTIVE before streaming.
    pub start_program: Option<String>,
    /// Give up when no packet was accepted (or the buffer did not shrink) for this long.
    pub stall_timeout: Duration,
    /// Wait for the stream buffer to empty after the last packet.
    pub wait_empty: bool,
}

impl Default for StreamOptions {
    fn default() -> Self {
        StreamOptions {
            channel: 1,
            packet_bytes: MAX_PROGRAM_STREAM_INPUT_SIZE,
            retry: Duration::from_micros(250),
            start_program: None,
            stall_timeout: Duration::from_secs(30),
            wait_empty: true,
        }
    }
}

/// Progress of a streaming run, reported about twice a second and at the end.
#[derive(Debug, Clone, Copy, Default)]
pub struct StreamProgress {
    pub bytes_sent: u64,
    pub bytes_total: u64,
    pub packets_sent: u64,
    /// Writes rejected with 0x708 (each one a warning 11012 in the channel).
    pub rejections: u64,
    pub elapsed: Duration,
    /// Round trip of a stream write (accepted or busy), µs: median and 99th percentile.
    pub(crate) write_rtt_us_p50: f64,
    pub(crate) write_rtt_us_p99: f64,
}

impl StreamProgress {
    pub(crate) fn bytes_per_second(&self) -> f64 {
        let s = self.elapsed.as_secs_f64();
        if s > 0.0 {
            self.bytes_sent as f64 / s
        } else {
            0.0
        }
    }
}

/// Why a streaming run failed.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    #[error(transparent)]
    Line(#[from] LineTooLong),
    #[error("{0}")]
    Client(#[from] ClientError),
    #[error("channel rejected packet {packet} with {result}")]
    Rejected { packet: usize, result: AdsResult },
    #[error("stream stalled: nothing accepted for {0:?} (is the streaming program running?)")]
    Stalled(Duration),
    #[error("channel error: {0}")]
    Channel(String),
    #[error("packet size {0} out of range 1..={MAX_PROGRAM_STREAM_INPUT_SIZE}")]
    PacketSize(usize),
}

fn group(channel: u16) -> u32 {
    GROUP_CHANNEL + u32::from(channel)
}

/// Start the streaming program: mode AUTOMATIC (0x104), program name (0x108), state ACTIVE
/// (0x105), as a PLC or HMI does.
pub fn start_program(client: &mut AdsClient, channel: u16, name: &str) -> Result<(), ClientError> {
    let g = group(channel);
    client.write(
        g,
        offset::COMMAND_MODE,
        &(Mode::Automatic as i32).to_le_bytes(),
    )?;
    client.write(g, offset::COMMAND_PROGRAM, name.as_bytes())?;
    client.write(
        g,
        offset::COMMAND_STATE,
        &(State::Active as i32).to_le_bytes(),
    )
}

/// Whether the channel runs a program (ACTIVE or HOLD), which will drain the stream buffer.
fn program_running(client: &mut AdsClient, channel: u16) -> Result<bool, ClientError> {
    let ms = client.read(group(channel), offset::MODE_STATE, 8)?;
    let [_, _, _, _, a, b, c, d] = ms[..] else {
        return Ok(false);
    };
    let s = State::from_i32(i32::from_le_bytes([a, b, c, d]));
    Ok(matches!(s, Some(State::Active | State::Hold)))
}

/// The channel's error text when it is in state ERROR.
fn channel_error(client: &mut AdsClient, channel: u16) -> Result<Option<String>, ClientError> {
    let g = group(channel);
    let ms = client.read(g, offset::MODE_STATE, 8)?;
    let [_, _, _, _, a, b, c, d] = ms[..] else {
        return Ok(None);
    };
    if State::from_i32(i32::from_le_bytes([a, b, c, d])) == Some(State::Error) {
        let text = client.read(g, offset::ERROR_MESSAGE, 256)?;
        let end = text.iter().position(|&b| b == 0).unwrap_or(text.len());
        return Ok(Some(String::from_utf8_lossy(&text[..end]).into_owned()));
    }
    Ok(None)
}

/// Stream `text` into the channel; `progress` is called about every 500 ms and once at the
/// end. Returns the final progress.
pub fn stream_text(
    client: &mut AdsClient,
    text: &[u8],
    opts: &StreamOptions,
    progress: &mut dyn FnMut(&StreamProgress),
) -> Result<StreamProgress, StreamError> {
    if opts.packet_bytes == 0 || opts.packet_bytes > MAX_PROGRAM_STREAM_INPUT_SIZE {
        return Err(StreamError::PacketSize(opts.packet_bytes));
    }
    let packets = packets(text, opts.packet_bytes)?;
    let g = group(opts.channel);
    if let Some(name) = &opts.start_program {
        start_program(client, opts.channel, name)?;
    }
    let start = Instant::now();
    let mut p = StreamProgress {
        bytes_total: packets.iter().map(|p| p.len() as u64).sum(),
        ..StreamProgress::default()
    };
    let mut last_report = start;
    let mut last_accept = start;
    let mut rtt = crate::vocab::stats::Histogram::new();
    for (i, packet) in packets.iter().enumerate() {
        loop {
            let sent = Instant::now();
            let r = client.write(g, offset::STREAM, packet);
            rtt.record(sent.elapsed());
            p.write_rtt_us_p50 = rtt.quantile_us(0.5);
            p.write_rtt_us_p99 = rtt.quantile_us(0.99);
            match r {
                Ok(()) => {
                    last_accept = Instant::now();
                    break;
                }
                Err(ClientError::Ads(AdsResult::BUSY)) => {
                    p.rejections += 1;
                    // The stall timer counts only while nothing will take the data: a
                    // running program drains the buffer, however long its current move.
                    if last_accept.elapsed() > opts.stall_timeout / 2
                        && program_running(client, opts.channel)?
                    {
                        last_accept = Instant::now();
                    }
                    if last_accept.elapsed() > opts.stall_timeout {
                        return Err(StreamError::Stalled(opts.stall_timeout));
                    }
                    spin_sleep::sleep(opts.retry);
                }
                Err(ClientError::Ads(result)) => {
                    if let Ok(Some(msg)) = channel_error(client, opts.channel) {
                        return Err(StreamError::Channel(msg));
                    }
                    return Err(StreamError::Rejected {
                        packet: i + 1,
                        result,
                    });
                }
                Err(e) => return Err(e.into()),
            }
            if last_report.elapsed() >= Duration::from_millis(500) {
                p.elapsed = start.elapsed();
                progress(&p);
                last_report = Instant::now();
            }
        }
        p.bytes_sent += packet.len() as u64;
        p.packets_sent += 1;
        if last_report.elapsed() >= Duration::from_millis(500) {
            p.elapsed = start.elapsed();
            progress(&p);
            last_report = Instant::now();
        }
    }
    if opts.wait_empty {
        wait_empty(client, opts, &mut p, start, progress)?;
    }
    if let Some(msg) = channel_error(client, opts.channel)? {
        return Err(StreamError::Channel(msg));
    }
    p.elapsed = start.elapsed();
    progress(&p);
    Ok(p)
}

/// Poll the fill-level extension until the buffer is empty. A device without the extension
/// (0x703, e.g. a real TwinCAT) ends the wait at once.
fn wait_empty(
    client: &mut AdsClient,
    opts: &StreamOptions,
    p: &mut StreamProgress,
    start: Instant,
    progress: &mut dyn FnMut(&StreamProgress),
) -> Result<(), StreamError> {
    let g = group(opts.channel);
    let mut last_used = u32::MAX;
    let mut last_change = Instant::now();
    let mut last_report = Instant::now();
    loop {
        let fill = match client.read(g, offset::STREAM_FILL, 8) {
            Ok(f) if f.len() == 8 => f,
            Ok(_) | Err(ClientError::Ads(AdsResult::INVALID_OFFSET)) => return Ok(()),
            Err(e) => return Err(e.into()),
        };
        let used = u32::from_le_bytes([fill[0], fill[1], fill[2], fill[3]]);
        if used == 0 {
            return Ok(());
        }
        if used != last_used
            || (last_change.elapsed() > opts.stall_timeout / 2
                && program_running(client, opts.channel)?)
        {
            last_used = used;
            last_change = Instant::now();
        } else if last_change.elapsed() > opts.stall_timeout {
            if let Some(msg) = channel_error(client, opts.channel)? {
                return Err(StreamError::Channel(msg));
            }
            return Err(StreamError::Stalled(opts.stall_timeout));
        }
        if last_report.elapsed() >= Duration::from_millis(500) {
            p.elapsed = start.elapsed();
            progress(p);
            last_report = Instant::now();
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The default target address: the CNC COM task on the server's default NetId.
pub fn default_target() -> AmsAddr {
    AmsAddr {
        net_id: crate::vocab::ams::DEFAULT_NET_ID,
        port: PORT_CNC_COM,
    }
}
