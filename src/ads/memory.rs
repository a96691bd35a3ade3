//! `MemoryBackend`: an in-memory stand-in channel behind the ADS object table, for tests and
//! for exercising ADS clients without the runtime.
//!
//! It is small but honest about the stream interface: a real 4094-byte buffer, the 992-byte
//! packet limit, CR LF checking (error 21476, state ERROR), 11012 warnings counted on full
//! writes, a mode/state machine with the ISG HLI numbers, and a drain thread that consumes whole
//! lines while the channel is ACTIVE (block counter, X/Y/Z positions from the words, M2/M30
//! ends the program). It does not interpret NC; the runtime does that.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard, Weak};
use std::time::Duration;

use super::backend::{
    mode, state, CncBackend, DeviceError, ErrorRecord, HmiOp, Status, StreamFill,
    StreamWriteOutcome,
};
use crate::channel::{HmiCommands, Mode, State};
use crate::source::stream::{MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_SIZE};

/// Message of error 21476.
pub const MSG_21476: &str = "21476 Streaming data does not contain a correct line end marker";

/// How fast the stand-in channel consumes stream lines.
#[derive(Debug, Clone, Copy)]
pub struct DrainRate {
    /// Lines consumed per tick while ACTIVE.
    pub lines_per_tick: usize,
    /// Tick period.
    pub period: Duration,
}

impl Default for DrainRate {
    fn default() -> Self {
        DrainRate {
            lines_per_tick: 4,
            period: Duration::from_millis(1),
        }
    }
}

/// One stand-in channel's state.
#[derive(Debug)]
struct MemChannel {
    buffer: VecDeque<u8>,
    mode: i32,
    state: i32,
    program: String,
    last_error: String,
    block_counter: u64,
    positions_mm: [f64; 3],
    override_percent: f64,
    ve: HashMap<String, f64>,
    warnings_11012: u64,
    hmi: HmiCommands,
    /// Errors raised (each 21476 counts one).
    errors_total: u64,
    /// Every line consumed, in order, for tests to compare with what was sent.
    consumed: Vec<u8>,
}

impl MemChannel {
    fn new() -> Self {
        MemChannel {
            buffer: VecDeque::with_capacity(MAX_PROGRAM_STREAM_SIZE),
            mode: mode::STANDBY,
            state: state::READY,
            program: String::new(),
            last_error: String::new(),
            block_counter: 0,
            positions_mm: [0.0; 3],
            override_percent: 100.0,
            ve: HashMap::new(),
            warnings_11012: 0,
            hmi: HmiCommands::default(),
            errors_total: 0,
            consumed: Vec::new(),
        }
    }

    /// Consume one whole line from the buffer, if one is there.
    fn consume_line(&mut self) -> bool {
        let Some(nl) = self.buffer.iter().position(|&b| b == b'\n') else {
            return false;
        };
        let line: Vec<u8> = self.buffer.drain(..=nl).collect();
        self.consumed.extend_from_slice(&line);
        let text = String::from_utf8_lossy(&line);
        let code = text.split(';').next().unwrap_or("").trim();
        if code.is_empty() {
            return true;
        }
        self.block_counter += 1;
        for word in code.split_whitespace() {
            let upper = word.to_ascii_uppercase();
            let axis = match upper.as_bytes().first() {
                Some(b'X') => Some(0),
                Some(b'Y') => Some(1),
                Some(b'Z') => Some(2),
                _ => None,
            };
            if let Some(i) = axis {
                if let Ok(v) = upper[1..].parse::<f64>() {
                    self.positions_mm[i] = v;
                }
            }
            if matches!(upper.as_str(), "M2" | "M02" | "M30") {
                self.state = state::READY;
            }
        }
        true
    }
}

/// The stand-in backend: `channels` channels of `MemChannel`, drained by one thread.
#[derive(Debug)]
pub struct MemoryBackend {
    channels: Vec<Mutex<MemChannel>>,
}

impl MemoryBackend {
    /// Create `channels` (≥ 1) stand-in channels and start their drain thread; the thread ends
    /// when the last `Arc` is dropped.
    pub fn new(channels: u16, rate: DrainRate) -> Arc<Self> {
        let backend = Arc::new(MemoryBackend {
            channels: (0..channels.max(1))
                .map(|_| Mutex::new(MemChannel::new()))
                .collect(),
        });
        let weak: Weak<MemoryBackend> = Arc::downgrade(&backend);
        std::thread::Builder::new()
            .name("memory-channel-drain".into())
            .spawn(move || loop {
                std::thread::sleep(rate.period);
                let Some(b) = weak.upgrade() else { return };
                for ch in &b.channels {
                    let mut c = lock(ch);
                    for _ in 0..rate.lines_per_tick {
                        if c.state != state::ACTIVE || !c.consume_line() {
                            break;
                        }
                    }
                }
            })
            .ok();
        backend
    }

    fn ch(&self, ch: u16) -> Result<MutexGuard<'_, MemChannel>, DeviceError> {
        let i = usize::from(ch)
            .checked_sub(1)
            .ok_or(DeviceError::NotFound)?;
        self.channels.get(i).map(lock).ok_or(DeviceError::NotFound)
    }

    /// How many writes were rejected with warning 11012 (stream full).
    pub fn warnings_11012(&self, ch: u16) -> u64 {
        self.ch(ch).map(|c| c.warnings_11012).unwrap_or(0)
    }

    /// Everything the channel has consumed from its stream so far.
    pub fn consumed(&self, ch: u16) -> Vec<u8> {
        self.ch(ch).map(|c| c.consumed.clone()).unwrap_or_default()
    }

    /// The program name last selected through 0x108.
    pub fn program(&self, ch: u16) -> String {
        self.ch(ch).map(|c| c.program.clone()).unwrap_or_default()
    }

    /// Current feed override in percent.
    pub fn override_percent(&self, ch: u16) -> f64 {
        self.ch(ch).map(|c| c.override_percent).unwrap_or(0.0)
    }
}

fn lock(m: &Mutex<MemChannel>) -> MutexGuard<'_, MemChannel> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// True when every line in `data` ends with CR LF and nothing follows the last one.
pub fn lines_end_with_crlf(data: &[u8]) -> bool {
    if !data.ends_with(b"\r\n") {
        return false;
    }
    data.iter().enumerate().all(|(i, &b)| match b {
        b'\n' => i > 0 && data[i - 1] == b'\r',
        b'\r' => data.get(i + 1) == Some(&b'\n'),
        _ => true,
    })
}

impl CncBackend for MemoryBackend {
    fn channel_count(&self) -> u16 {
        self.channels.len() as u16
    }

    fn stream_write(&self, ch: u16, data: &[u8]) -> StreamWriteOutcome {
        let mut c = match self.ch(ch) {
            Ok(c) => c,
            Err(e) => return StreamWriteOutcome::Refused(e),
        };
        if data.is_empty() || data.len() > MAX_PROGRAM_STREAM_INPUT_SIZE {
            return StreamWriteOutcome::BadSize;
        }
        if !lines_end_with_crlf(data) {
            c.last_error = MSG_21476.to_string();
            c.errors_total += 1;
            c.state = state::ERROR;
            c.buffer.clear();
            return StreamWriteOutcome::NoLineEnd;
        }
        if c.buffer.len() + data.len() > MAX_PROGRAM_STREAM_SIZE {
            c.warnings_11012 += 1;
            return StreamWriteOutcome::Full;
        }
        c.buffer.extend(data.iter().copied());
        StreamWriteOutcome::Accepted
    }

    fn mode_state(&self, ch: u16) -> Result<(i32, i32), DeviceError> {
        let c = self.ch(ch)?;
        Ok((c.mode, c.state))
    }

    fn command_mode(&self, ch: u16, m: i32) -> Result<(), DeviceError> {
        if crate::channel::Mode::from_i32(m).is_none() {
            return Err(DeviceError::InvalidValue);
        }
        let mut c = self.ch(ch)?;
        if c.state == state::ACTIVE || c.state == state::HOLD {
            return Err(DeviceError::NotReady);
        }
        c.mode = m;
        Ok(())
    }

    fn command_state(&self, ch: u16, s: i32) -> Result<(), DeviceError> {
        if !(state::DESELECTED..=state::ERROR).contains(&s) {
            return Err(DeviceError::InvalidValue);
        }
        let mut c = self.ch(ch)?;
        if s == state::ACTIVE {
            if c.mode != mode::AUTOMATIC || c.program.is_empty() || c.state == state::ERROR {
                return Err(DeviceError::NotReady);
            }
        } else if s == state::ERROR {
            return Err(DeviceError::InvalidValue);
        }
        c.state = s;
        Ok(())
    }

    fn command_program(&self, ch: u16, name: &str) -> Result<(), DeviceError> {
        self.ch(ch)?.program = name.to_string();
        Ok(())
    }

    fn hold(&self, ch: u16) -> Result<(), DeviceError> {
        let mut c = self.ch(ch)?;
        if c.state != state::ACTIVE {
            return Err(DeviceError::NotReady);
        }
        c.state = state::HOLD;
        Ok(())
    }

    fn resume(&self, ch: u16) -> Result<(), DeviceError> {
        let mut c = self.ch(ch)?;
        if c.state != state::HOLD {
            return Err(DeviceError::NotReady);
        }
        c.state = state::ACTIVE;
        Ok(())
    }

    fn reset(&self, ch: u16) -> Result<(), DeviceError> {
        let mut c = self.ch(ch)?;
        c.buffer.clear();
        c.state = state::READY;
        c.last_error.clear();
        Ok(())
    }

    fn last_error(&self, ch: u16) -> Result<String, DeviceError> {
        Ok(self.ch(ch)?.last_error.clone())
    }

    fn stream_fill(&self, ch: u16) -> Result<StreamFill, DeviceError> {
        let c = self.ch(ch)?;
        Ok(StreamFill {
            used_bytes: c.buffer.len() as u32,
            free_bytes: (MAX_PROGRAM_STREAM_SIZE - c.buffer.len()) as u32,
        })
    }

    fn block_counter(&self, ch: u16) -> Result<u64, DeviceError> {
        Ok(self.ch(ch)?.block_counter)
    }

    fn positions(&self, ch: u16) -> Result<Vec<f64>, DeviceError> {
        Ok(self.ch(ch)?.positions_mm.to_vec())
    }

    fn set_override(&self, ch: u16, percent: f64) -> Result<(), DeviceError> {
        self.ch(ch)?.override_percent = percent;
        Ok(())
    }

    fn read_ve(&self, ch: u16, name: &str) -> Result<f64, DeviceError> {
        self.ch(ch)?
            .ve
            .get(&name.to_ascii_uppercase())
            .copied()
            .ok_or(DeviceError::NotFound)
    }

    fn write_ve(&self, ch: u16, name: &str, value: f64) -> Result<(), DeviceError> {
        self.ch(ch)?.ve.insert(name.to_ascii_uppercase(), value);
        Ok(())
    }

    fn view(&self, ch: u16) -> Result<Status, DeviceError> {
        Ok(self.ch(ch)?.view())
    }

    fn hmi(&self, ch: u16, op: HmiOp) -> Result<(), DeviceError> {
        let mut c = self.ch(ch)?;
        match op {
            HmiOp::SingleBlock(on) => c.hmi.single_block = on,
            HmiOp::OptionalStop(on) => c.hmi.optional_stop = on,
            HmiOp::SkipLevels(mask) => c.hmi.skip_levels = mask & 0x3FF,
            HmiOp::ExecutionMode(m) if m & !1 == 0 => c.hmi.execution_mode = m,
            HmiOp::ExecutionMode(_) => return Err(DeviceError::InvalidValue),
            HmiOp::Search(s) => c.hmi.search = s,
            HmiOp::ResetCycleTimes => {}
        }
        Ok(())
    }

    fn error_record(&self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError> {
        let c = self.ch(ch)?;
        let newest = index + 1 == c.errors_total;
        Ok(ErrorRecord {
            total: c.errors_total,
            error: newest.then(|| (21476, MSG_21476.to_string())),
        })
    }
}

impl MemChannel {
    /// The snapshot the object table reads; what the stand-in does not model stays at rest.
    fn view(&self) -> Status {
        Status {
            mode: Mode::from_i32(self.mode).unwrap_or(Mode::Standby),
            state: State::from_i32(self.state).unwrap_or(State::Ready),
            block_counter: self.block_counter,
            stream_used: self.buffer.len(),
            stream_free: MAX_PROGRAM_STREAM_SIZE - self.buffer.len(),
            positions: ['X', 'Y', 'Z'].into_iter().zip(self.positions_mm).collect(),
            last_error: (!self.last_error.is_empty()).then(|| (21476, MSG_21476.to_string())),
            override_pct: self.override_percent,
            blocks: self.block_counter,
            tick: 0,
            period: Duration::from_millis(1),
            cycle_times: Default::default(),
            program: (self.state == state::ACTIVE).then(|| self.program.clone()),
            active_block: None,
            feed_mm_per_min: 0.0,
            velocity_mm_per_s: 0.0,
            hmi: self.hmi,
            searching: false,
            ipo_blocks: 0,
            errors_total: self.errors_total,
            pcs_positions: ['X', 'Y', 'Z'].into_iter().zip(self.positions_mm).collect(),
            message: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crlf_rule() {
        assert!(lines_end_with_crlf(b"N10 X1\r\nN20 Y2\r\n"));
        assert!(!lines_end_with_crlf(b"N10 X1\nN20 Y2\r\n"));
        assert!(!lines_end_with_crlf(b"N10 X1\r\nN20"));
        assert!(!lines_end_with_crlf(b"N10\rX1\r\n"));
        assert!(!lines_end_with_crlf(b""));
    }

    #[test]
    fn buffer_holds_4094_bytes_and_then_warns() {
        let b = MemoryBackend::new(1, DrainRate::default());
        let line = [vec![b'X'; 990], b"\r\n".to_vec()].concat();
        for _ in 0..4 {
            assert_eq!(b.stream_write(1, &line), StreamWriteOutcome::Accepted);
        }
        assert_eq!(b.stream_write(1, &line), StreamWriteOutcome::Full);
        assert_eq!(b.warnings_11012(1), 1);
        assert_eq!(
            b.stream_fill(1).unwrap().free_bytes as usize,
            MAX_PROGRAM_STREAM_SIZE - 4 * MAX_PROGRAM_STREAM_INPUT_SIZE
        );
        assert_eq!(b.stream_write(1, &[b'X'; 993]), StreamWriteOutcome::BadSize);
    }
}
