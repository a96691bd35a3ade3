//! Per-command ADS payloads: decoding requests and encoding responses (server side), and the
//! reverse (client side). Every length field is checked against the bytes actually present;
//! a short or inconsistent payload is a `PayloadError`, answered with 0x705, never a panic.

use super::result::AdsResult;

/// The request payload of one ADS command, decoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    ReadDeviceInfo,
    Read {
        group: u32,
        offset: u32,
        length: u32,
    },
    Write {
        group: u32,
        offset: u32,
        data: Vec<u8>,
    },
    ReadState,
    WriteControl {
        ads_state: u16,
        device_state: u16,
        data: Vec<u8>,
    },
    AddNotification(NotificationRequest),
    DelNotification {
        handle: u32,
    },
    ReadWrite {
        group: u32,
        offset: u32,
        read_length: u32,
        data: Vec<u8>,
    },
}

/// AddDeviceNotification parameters as they arrive on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotificationRequest {
    pub group: u32,
    pub offset: u32,
    pub length: u32,
    /// Transmission mode: 3/5 server cycle, 4/6 server on change (1/2 client modes are
    /// treated as 3/4).
    pub mode: u32,
    /// Maximum delay in 100 ns units (ADS convention); we send at once, so it is only kept.
    pub(crate) max_delay_100ns: u32,
    /// Cycle time in 100 ns units (ADS convention).
    pub(crate) cycle_time_100ns: u32,
}

/// A request payload that does not hold what its command needs.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PayloadError {
    #[error("payload of {got} bytes is shorter than the {need} bytes the command needs")]
    Short { need: usize, got: usize },
    #[error("length field says {declared} bytes but {present} follow")]
    LengthMismatch { declared: usize, present: usize },
}

impl PayloadError {
    /// The ADS result these errors are answered with.
    pub fn result(&self) -> AdsResult {
        AdsResult::INVALID_SIZE
    }
}

/// A little-endian cursor over untrusted bytes; every read is checked.
pub(crate) struct Cursor<'a> {
    buf: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    pub(crate) fn new(buf: &'a [u8]) -> Self {
        Cursor { buf, at: 0 }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], PayloadError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.buf.len());
        match end {
            Some(end) => {
                let s = &self.buf[self.at..end];
                self.at = end;
                Ok(s)
            }
            None => Err(PayloadError::Short {
                need: self.at.saturating_add(n),
                got: self.buf.len(),
            }),
        }
    }

    pub(crate) fn u16(&mut self) -> Result<u16, PayloadError> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub(crate) fn u32(&mut self) -> Result<u32, PayloadError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub(crate) fn u64(&mut self) -> Result<u64, PayloadError> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    /// Exactly `declared` bytes, which must be all that is left.
    fn rest_exact(&mut self, declared: u32) -> Result<Vec<u8>, PayloadError> {
        let present = self.buf.len() - self.at;
        if declared as usize != present {
            return Err(PayloadError::LengthMismatch {
                declared: declared as usize,
                present,
            });
        }
        Ok(self.take(present)?.to_vec())
    }

    pub(crate) fn bytes(&mut self, n: usize) -> Result<&'a [u8], PayloadError> {
        self.take(n)
    }
}

/// Decode a request payload for `command` (1..=9 except 8). `None` for commands a server does
/// not accept as requests (DeviceNotification and unknown ids): the caller answers 0x701.
pub fn decode_request(command: u16, data: &[u8]) -> Option<Result<Request, PayloadError>> {
    let mut c = Cursor::new(data);
    let r = match command {
        1 => Ok(Request::ReadDeviceInfo),
        2 => (|| {
            Ok(Request::Read {
                group: c.u32()?,
                offset: c.u32()?,
                length: c.u32()?,
            })
        })(),
        3 => (|| {
            let group = c.u32()?;
            let offset = c.u32()?;
            let len = c.u32()?;
            Ok(Request::Write {
                group,
                offset,
                data: c.rest_exact(len)?,
            })
        })(),
        4 => Ok(Request::ReadState),
        5 => (|| {
            let ads_state = c.u16()?;
            let device_state = c.u16()?;
            let len = c.u32()?;
            Ok(Request::WriteControl {
                ads_state,
                device_state,
                data: c.rest_exact(len)?,
            })
        })(),
        6 => (|| {
            let n = NotificationRequest {
                group: c.u32()?,
                offset: c.u32()?,
                length: c.u32()?,
                mode: c.u32()?,
                max_delay_100ns: c.u32()?,
                cycle_time_100ns: c.u32()?,
            };
            // 16 reserved bytes; clients send them, but a missing tail costs nothing.
            Ok(Request::AddNotification(n))
        })(),
        7 => (|| Ok(Request::DelNotification { handle: c.u32()? }))(),
        9 => (|| {
            let group = c.u32()?;
            let offset = c.u32()?;
            let read_length = c.u32()?;
            let write_len = c.u32()?;
            Ok(Request::ReadWrite {
                group,
                offset,
                read_length,
                data: c.rest_exact(write_len)?,
            })
        })(),
        _ => return None,
    };
    Some(r)
}

/// Responses, encoded exactly as long as clients expect (docs/ads-wire.md, rule 4).
pub mod response {
    use super::AdsResult;

    /// Write, WriteControl, DelDeviceNotification: the result alone, 4 bytes.
    pub(crate) fn result_only(result: AdsResult) -> Vec<u8> {
        result.0.to_le_bytes().to_vec()
    }

    /// ReadDeviceInfo: 24 bytes; `name` is cut to 15 bytes so a NUL always ends it.
    pub(crate) fn device_info(major: u8, minor: u8, build: u16, name: &str) -> Vec<u8> {
        let mut out = Vec::with_capacity(24);
        out.extend_from_slice(&0u32.to_le_bytes());
        out.push(major);
        out.push(minor);
        out.extend_from_slice(&build.to_le_bytes());
        let mut field = [0u8; 16];
        for (d, s) in field.iter_mut().zip(name.bytes().take(15)) {
            *d = s;
        }
        out.extend_from_slice(&field);
        out
    }

    /// Read and ReadWrite: result, length, data (empty data on error).
    pub(crate) fn with_data(result: AdsResult, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(8 + data.len());
        out.extend_from_slice(&result.0.to_le_bytes());
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(data);
        out
    }

    /// ReadState: result, ADS state, device state (8 bytes).
    pub fn state(ads_state: u16, device_state: u16) -> Vec<u8> {
        let mut out = Vec::with_capacity(8);
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&ads_state.to_le_bytes());
        out.extend_from_slice(&device_state.to_le_bytes());
        out
    }

    /// AddDeviceNotification: result, handle (8 bytes; handle 0 on error).
    pub fn handle(result: AdsResult, handle: u32) -> Vec<u8> {
        let mut out = Vec::with_capacity(8);
        out.extend_from_slice(&result.0.to_le_bytes());
        out.extend_from_slice(&handle.to_le_bytes());
        out
    }

    /// DeviceNotification (server → client): one stamp holding the given samples.
    pub fn notification(filetime_100ns: u64, samples: &[(u32, &[u8])]) -> Vec<u8> {
        let body_len: usize = 4 + 8 + 4 + samples.iter().map(|(_, d)| 8 + d.len()).sum::<usize>();
        let mut out = Vec::with_capacity(4 + body_len);
        out.extend_from_slice(&(body_len as u32).to_le_bytes());
        out.extend_from_slice(&1u32.to_le_bytes());
        out.extend_from_slice(&filetime_100ns.to_le_bytes());
        out.extend_from_slice(&(samples.len() as u32).to_le_bytes());
        for (handle, data) in samples {
            out.extend_from_slice(&handle.to_le_bytes());
            out.extend_from_slice(&(data.len() as u32).to_le_bytes());
            out.extend_from_slice(data);
        }
        out
    }
}

/// Requests, encoded by the client.
pub mod request {
    /// Read: group, offset, length.
    pub fn read(group: u32, offset: u32, length: u32) -> Vec<u8> {
        [group, offset, length]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    /// Write: group, offset, length, data.
    pub fn write(group: u32, offset: u32, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(12 + data.len());
        for v in [group, offset, data.len() as u32] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(data);
        out
    }

    /// ReadWrite: group, offset, read length, write length, data.
    pub fn read_write(group: u32, offset: u32, read_length: u32, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(16 + data.len());
        for v in [group, offset, read_length, data.len() as u32] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(data);
        out
    }

    /// AddDeviceNotification: group, offset, length, mode, max delay, cycle time, 16 reserved.
    pub fn add_notification(
        group: u32,
        offset: u32,
        length: u32,
        mode: u32,
        max_delay_100ns: u32,
        cycle_time_100ns: u32,
    ) -> Vec<u8> {
        let mut out: Vec<u8> = [
            group,
            offset,
            length,
            mode,
            max_delay_100ns,
            cycle_time_100ns,
        ]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
        out.extend_from_slice(&[0u8; 16]);
        out
    }
}

/// Decode a response that carries `result, length, data` (Read, ReadWrite); the data must be
/// exactly as long as declared.
pub fn decode_data_response(data: &[u8]) -> Result<(AdsResult, Vec<u8>), PayloadError> {
    let mut c = Cursor::new(data);
    let result = AdsResult(c.u32()?);
    if data.len() == 4 && !result.is_ok() {
        return Ok((result, Vec::new()));
    }
    let len = c.u32()?;
    Ok((result, c.rest_exact(len)?))
}

/// Decode the leading result of any response.
pub fn decode_result(data: &[u8]) -> Result<AdsResult, PayloadError> {
    Ok(AdsResult(Cursor::new(data).u32()?))
}

/// One sample of a DeviceNotification.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sample {
    pub handle: u32,
    pub(crate) filetime_100ns: u64,
    pub data: Vec<u8>,
}

/// Decode a DeviceNotification payload into its samples. The sample count is untrusted, so
/// samples are pushed as they are read, never pre-allocated from the count.
pub fn decode_notification(data: &[u8]) -> Result<Vec<Sample>, PayloadError> {
    let mut c = Cursor::new(data);
    let len = c.u32()? as usize;
    if len != data.len() - 4 {
        return Err(PayloadError::LengthMismatch {
            declared: len,
            present: data.len() - 4,
        });
    }
    let stamps = c.u32()?;
    let mut out = Vec::new();
    for _ in 0..stamps {
        let time = c.u64()?;
        let samples = c.u32()?;
        for _ in 0..samples {
            let handle = c.u32()?;
            let size = c.u32()? as usize;
            out.push(Sample {
                handle,
                filetime_100ns: time,
                data: c.bytes(size)?.to_vec(),
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_request_round_trips_and_checks_its_length() {
        let bytes = request::write(0x20101, 0x90, b"N10 X1\r\n");
        assert_eq!(
            decode_request(3, &bytes),
            Some(Ok(Request::Write {
                group: 0x20101,
                offset: 0x90,
                data: b"N10 X1\r\n".to_vec()
            }))
        );
        let mut lying = bytes.clone();
        lying[8] = 200;
        assert!(matches!(
            decode_request(3, &lying),
            Some(Err(PayloadError::LengthMismatch { .. }))
        ));
        for cut in 0..12 {
            assert!(matches!(
                decode_request(3, &bytes[..cut]),
                Some(Err(PayloadError::Short { .. }))
            ));
        }
    }

    #[test]
    fn every_command_survives_every_truncation() {
        let full: Vec<u8> = (0u8..64).collect();
        for cmd in 0..12u16 {
            for cut in 0..full.len() {
                let _ = decode_request(cmd, &full[..cut]);
            }
        }
        assert_eq!(decode_request(8, &[]), None);
        assert_eq!(decode_request(10, &[]), None);
    }

    #[test]
    fn response_sizes_are_exact() {
        assert_eq!(response::result_only(AdsResult::OK).len(), 4);
        assert_eq!(response::device_info(0, 1, 0, "ncchannel 0.1.0").len(), 24);
        assert_eq!(
            response::device_info(0, 1, 0, "a name far longer than sixteen")[23],
            0
        );
        assert_eq!(response::with_data(AdsResult::OK, &[1, 2, 3]).len(), 11);
        assert_eq!(response::state(5, 0).len(), 8);
    }

    #[test]
    fn notification_round_trips() {
        let payload = response::notification(42, &[(7, &[1, 2]), (9, &[3])]);
        let samples = decode_notification(&payload).unwrap();
        assert_eq!(samples.len(), 2);
        assert_eq!(samples[0].handle, 7);
        assert_eq!(samples[0].data, vec![1, 2]);
        assert_eq!(samples[1].filetime_100ns, 42);
        // A huge sample count with no samples behind it is an error, not an allocation.
        let mut hostile = 8u32.to_le_bytes().to_vec();
        hostile.extend_from_slice(&u32::MAX.to_le_bytes());
        hostile.extend_from_slice(&[0, 0, 0, 0]);
        assert!(decode_notification(&hostile).is_err());
    }
}
