//! The AMS/TCP codec: AmsNetId, the 6-byte AMS/TCP header and the 32-byte AMS header, and a
//! decoder that cuts frames out of a byte buffer by their length field.
//!
//! The decoder is written mini-redis style: `Ok(None)` means "not enough bytes yet, read more",
//! an error means the stream is malformed and the connection must be closed. The length field is
//! checked against a configured maximum *before* anything waits for (or allocates) that many
//! bytes, so a hostile length can never make the server reserve memory.

use std::fmt;

use crate::vocab::ams::AmsNetId;

/// Size of the AMS/TCP header: u16 reserved + u32 length.
pub(crate) const TCP_HEADER_LEN: usize = 6;
/// Size of the AMS header that follows it.
pub(crate) const AMS_HEADER_LEN: usize = 32;

/// State flags of a request (ADS command, TCP transport).
pub const FLAGS_REQUEST: u16 = 0x0004;
/// State flags of a response; clients (adslib, `ads`) insist on exactly this value.
pub(crate) const FLAGS_RESPONSE: u16 = 0x0005;

/// AMS router-level error in the header: the target AMS port does not exist.
pub(crate) const AMS_ERR_PORT_NOT_FOUND: u32 = 6;
/// AMS router-level error in the header: the target machine (NetId) is not this one.
pub(crate) const AMS_ERR_MACHINE_NOT_FOUND: u32 = 7;

/// An AMS address: NetId plus AMS port (553 is the CNC's COM task).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AmsAddr {
    pub net_id: AmsNetId,
    pub port: u16,
}

impl fmt::Display for AmsAddr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.net_id, self.port)
    }
}

/// ADS command ids (AMS header offset 16).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandId {
    ReadDeviceInfo,
    Read,
    Write,
    ReadState,
    WriteControl,
    AddDeviceNotification,
    DelDeviceNotification,
    DeviceNotification,
    ReadWrite,
    /// Any other number; answered with 0x701 "service not supported".
    Other(u16),
}

impl CommandId {
    pub fn from_u16(v: u16) -> Self {
        match v {
            1 => CommandId::ReadDeviceInfo,
            2 => CommandId::Read,
            3 => CommandId::Write,
            4 => CommandId::ReadState,
            5 => CommandId::WriteControl,
            6 => CommandId::AddDeviceNotification,
            7 => CommandId::DelDeviceNotification,
            8 => CommandId::DeviceNotification,
            9 => CommandId::ReadWrite,
            other => CommandId::Other(other),
        }
    }

    pub fn to_u16(self) -> u16 {
        match self {
            CommandId::ReadDeviceInfo => 1,
            CommandId::Read => 2,
            CommandId::Write => 3,
            CommandId::ReadState => 4,
            CommandId::WriteControl => 5,
            CommandId::AddDeviceNotification => 6,
            CommandId::DelDeviceNotification => 7,
            CommandId::DeviceNotification => 8,
            CommandId::ReadWrite => 9,
            CommandId::Other(v) => v,
        }
    }
}

/// The 32-byte AMS header. `data_len` is not stored: it is always the payload's length.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AmsHeader {
    pub target: AmsAddr,
    pub source: AmsAddr,
    pub command: CommandId,
    pub state_flags: u16,
    /// Router-level error (6 port not found, 7 machine not found); 0 otherwise.
    pub error: u32,
    /// Chosen by the requester, echoed in the response so it can pair them.
    pub invoke_id: u32,
}

impl AmsHeader {
    /// The header of the response to this request: addresses swapped byte for byte, command
    /// and invoke id echoed, flags exactly 0x0005.
    pub fn response(&self, error: u32) -> AmsHeader {
        AmsHeader {
            target: self.source,
            source: self.target,
            command: self.command,
            state_flags: FLAGS_RESPONSE,
            error,
            invoke_id: self.invoke_id,
        }
    }
}

/// One frame cut out of the byte stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Frame {
    /// An ADS command (reserved field 0).
    Ams { header: AmsHeader, data: Vec<u8> },
    /// An AMS router command (reserved field ≠ 0, e.g. 0x1000 "port connect"); the body is
    /// whatever followed the AMS/TCP header.
    Router { command: u16, body: Vec<u8> },
}

/// A malformed byte stream; the connection that sent it is closed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    #[error("AMS/TCP length {length} exceeds the maximum frame size {max} bytes")]
    TooLong { length: usize, max: usize },
    #[error("AMS/TCP length {length} is shorter than the 32-byte AMS header")]
    TooShort { length: usize },
    #[error("AMS header data length {data_len} does not match AMS/TCP length {length} - 32")]
    Inconsistent { length: usize, data_len: usize },
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn addr_at(b: &[u8], at: usize) -> AmsAddr {
    let mut id = [0u8; 6];
    id.copy_from_slice(&b[at..at + 6]);
    AmsAddr {
        net_id: AmsNetId(id),
        port: u16_at(b, at + 6),
    }
}

/// Try to cut one frame off the front of `buf`.
///
/// Returns `Ok(Some((frame, consumed)))`, `Ok(None)` when more bytes are needed, or an error
/// when the stream is malformed. `max_frame_bytes` bounds the AMS/TCP length field.
pub fn decode(buf: &[u8], max_frame_bytes: usize) -> Result<Option<(Frame, usize)>, FrameError> {
    if buf.len() < TCP_HEADER_LEN {
        return Ok(None);
    }
    let reserved = u16_at(buf, 0);
    let length = u32_at(buf, 2) as usize;
    if length > max_frame_bytes {
        return Err(FrameError::TooLong {
            length,
            max: max_frame_bytes,
        });
    }
    if reserved == 0 && length < AMS_HEADER_LEN {
        return Err(FrameError::TooShort { length });
    }
    let total = TCP_HEADER_LEN + length;
    if buf.len() < total {
        return Ok(None);
    }
    let body = &buf[TCP_HEADER_LEN..total];
    if reserved != 0 {
        return Ok(Some((
            Frame::Router {
                command: reserved,
                body: body.to_vec(),
            },
            total,
        )));
    }
    let data_len = u32_at(body, 20) as usize;
    if data_len != length - AMS_HEADER_LEN {
        return Err(FrameError::Inconsistent { length, data_len });
    }
    let header = AmsHeader {
        target: addr_at(body, 0),
        source: addr_at(body, 8),
        command: CommandId::from_u16(u16_at(body, 16)),
        state_flags: u16_at(body, 18),
        error: u32_at(body, 24),
        invoke_id: u32_at(body, 28),
    };
    Ok(Some((
        Frame::Ams {
            header,
            data: body[AMS_HEADER_LEN..].to_vec(),
        },
        total,
    )))
}

/// Encode one ADS frame (AMS/TCP header + AMS header + data) into a fresh buffer.
pub fn encode(header: &AmsHeader, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(TCP_HEADER_LEN + AMS_HEADER_LEN + data.len());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&((AMS_HEADER_LEN + data.len()) as u32).to_le_bytes());
    for addr in [header.target, header.source] {
        out.extend_from_slice(&addr.net_id.0);
        out.extend_from_slice(&addr.port.to_le_bytes());
    }
    out.extend_from_slice(&header.command.to_u16().to_le_bytes());
    out.extend_from_slice(&header.state_flags.to_le_bytes());
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(&header.error.to_le_bytes());
    out.extend_from_slice(&header.invoke_id.to_le_bytes());
    out.extend_from_slice(data);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_header() -> AmsHeader {
        AmsHeader {
            target: AmsAddr {
                net_id: "5.1.2.3.1.1".parse().unwrap(),
                port: 553,
            },
            source: AmsAddr {
                net_id: "10.0.0.7.1.1".parse().unwrap(),
                port: 32905,
            },
            command: CommandId::Write,
            state_flags: FLAGS_REQUEST,
            error: 0,
            invoke_id: 0xDEAD_BEEF,
        }
    }

    #[test]
    fn encode_then_decode_is_identity_and_partial_frames_wait() {
        let h = sample_header();
        let bytes = encode(&h, b"payload");
        assert_eq!(bytes.len(), 6 + 32 + 7);
        for cut in 0..bytes.len() {
            assert_eq!(decode(&bytes[..cut], 65536), Ok(None), "cut at {cut}");
        }
        let (frame, used) = decode(&bytes, 65536).unwrap().unwrap();
        assert_eq!(used, bytes.len());
        assert_eq!(
            frame,
            Frame::Ams {
                header: h,
                data: b"payload".to_vec()
            }
        );
    }

    #[test]
    fn two_frames_in_one_buffer_are_cut_one_by_one() {
        let mut bytes = encode(&sample_header(), b"a");
        let second = encode(&sample_header(), b"bc");
        bytes.extend_from_slice(&second);
        let (_, used) = decode(&bytes, 65536).unwrap().unwrap();
        let (frame, used2) = decode(&bytes[used..], 65536).unwrap().unwrap();
        assert_eq!(used + used2, bytes.len());
        assert!(matches!(frame, Frame::Ams { data, .. } if data == b"bc"));
    }

    #[test]
    fn hostile_lengths_are_errors_before_any_wait() {
        let mut bytes = vec![0, 0];
        bytes.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            decode(&bytes, 65536),
            Err(FrameError::TooLong { .. })
        ));
        let mut short = vec![0, 0];
        short.extend_from_slice(&4u32.to_le_bytes());
        assert_eq!(
            decode(&short, 65536),
            Err(FrameError::TooShort { length: 4 })
        );
        let mut bad = encode(&sample_header(), b"abc");
        bad[6 + 20] = 9; // data length 9 but only 3 bytes follow
        assert!(matches!(
            decode(&bad, 65536),
            Err(FrameError::Inconsistent { .. })
        ));
    }

    #[test]
    fn router_commands_are_framed_by_length() {
        let bytes = [0x00, 0x10, 2, 0, 0, 0, 0, 0];
        let (frame, used) = decode(&bytes, 65536).unwrap().unwrap();
        assert_eq!(used, 8);
        assert_eq!(
            frame,
            Frame::Router {
                command: 0x1000,
                body: vec![0, 0]
            }
        );
    }

    #[test]
    fn response_header_swaps_addresses_and_echoes() {
        let h = sample_header();
        let r = h.response(0);
        assert_eq!(r.target, h.source);
        assert_eq!(r.source, h.target);
        assert_eq!(r.invoke_id, h.invoke_id);
        assert_eq!(r.command, h.command);
        assert_eq!(r.state_flags, 0x0005);
    }
}
