//! ADS sum commands: many reads, writes or read-writes in one ReadWrite request, each
//! sub-request served by the port's own objects in order and answered with its own result.
//!
//! Layouts (Beckhoff InfoSys "ADS Sum Command" / `tc3_adsdll2` 9007199379576075; AdsLib
//! `AdsDef.h` `ADSIGRP_SUMUP_*`; `stlehmann/pyads` `adsSumRead`/`adsSumWrite`,
//! `jisotalo/ads-client` `ADS_RESERVED_INDEX_GROUPS`); the index offset is the sub-request
//! count:
//!
//! | group | written | read back |
//! |---|---|---|
//! | 0xF080 read | n × (group, offset, length) | n × result, then each sub-read's data in a slot of its requested length |
//! | 0xF081 write | n × (group, offset, length), then the data | n × result |
//! | 0xF082 read-write | n × (group, offset, read length, write length), then the write data | n × (result, length), then the data read |
//! | 0xF083 read ex | as 0xF080 | n × (result, length), then slots of the requested lengths |
//! | 0xF084 read ex 2 | as 0xF080 | n × (result, length), then the data read |
//!
//! | 0xF085 add notifications | n × AddDeviceNotification request (group, offset, length, mode, max delay, cycle time, 16 reserved bytes) | n × (result, handle) |
//! | 0xF086 delete notifications | n × handle | n × result |
//!
//! Handles go through these: 0xF082 with 0xF003 sub-requests creates many, 0xF081 with 0xF006
//! releases many. 0xF085/0xF086 (AdsLib `ADSIGRP_SUMUP_ADDDEVNOTE`/`ADSIGRP_SUMUP_DELDEVNOTE`,
//! the layout the `ads` crate's `Device::add_notification_multi` and
//! `delete_notification_multi` write) reach the connection's notification table, which this
//! layer does not see: [`add_notifications`] and [`delete_notifications`] take it as a closure,
//! and [`execute`] answers them 0x701.

use super::payload::{Cursor, NotificationRequest};
use super::result::AdsResult;

pub(crate) const READ: u32 = 0xF080;
pub(crate) const WRITE: u32 = 0xF081;
pub(crate) const READ_WRITE: u32 = 0xF082;
pub(crate) const READ_EX: u32 = 0xF083;
pub(crate) const READ_EX2: u32 = 0xF084;
pub(crate) const ADD_NOTIFICATIONS: u32 = 0xF085;
pub(crate) const DELETE_NOTIFICATIONS: u32 = 0xF086;
/// Sub-requests in one sum command: Beckhoff recommends at most 500 (pyads
/// `MAX_ADS_SUB_COMMANDS`); more is 0x706.
pub(crate) const MAX_SUB_REQUESTS: u32 = 500;
/// Bytes of one sum reply (results and data); a request that would read more is 0x705.
pub(crate) const MAX_REPLY_BYTES: usize = 256 * 1024;

/// The objects of one AMS port, as the sub-requests reach them.
pub(crate) trait Port {
    fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult>;
    fn write(&self, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult>;
    fn read_write(
        &self,
        group: u32,
        offset: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult>;
}

/// Whether `group` is a sum command's.
pub(crate) fn is_sum(group: u32) -> bool {
    (READ..=DELETE_NOTIFICATIONS).contains(&group)
}

/// Serve sum command `group` with `count` sub-requests described by `data`; the reply is at
/// most `read_length` bytes. A malformed request as a whole is one ADS error; a failing
/// sub-request is its own result, the others are served.
pub(crate) fn execute(
    port: &dyn Port,
    group: u32,
    count: u32,
    read_length: u32,
    data: &[u8],
) -> Result<Vec<u8>, AdsResult> {
    if count == 0 || count > MAX_SUB_REQUESTS {
        return Err(AdsResult::INVALID_DATA);
    }
    let budget = (read_length as usize).min(MAX_REPLY_BYTES);
    match group {
        READ | READ_EX | READ_EX2 => read(port, group, count, budget, data),
        WRITE => write(port, count, budget, data),
        READ_WRITE => read_write(port, count, budget, data),
        ADD_NOTIFICATIONS | DELETE_NOTIFICATIONS => Err(AdsResult::SERVICE_NOT_SUPPORTED),
        _ => Err(AdsResult::INVALID_GROUP),
    }
}

/// One sub-request's address and lengths, as written.
struct Sub {
    group: u32,
    offset: u32,
    read_length: u32,
    write_length: u32,
}

/// The `count` heads (`words` u32 each) at the start of `data`, and the bytes after them.
fn heads(data: &[u8], count: u32, words: usize) -> Result<(Vec<Sub>, &[u8]), AdsResult> {
    let mut c = Cursor::new(data);
    let mut subs = Vec::with_capacity(count as usize);
    let short = |_| AdsResult::INVALID_SIZE;
    for _ in 0..count {
        let group = c.u32().map_err(short)?;
        let offset = c.u32().map_err(short)?;
        let read_length = c.u32().map_err(short)?;
        let write_length = if words == 4 {
            c.u32().map_err(short)?
        } else {
            0
        };
        subs.push(Sub {
            group,
            offset,
            read_length,
            write_length,
        });
    }
    let used = subs.len() * words * 4;
    Ok((subs, &data[used..]))
}

/// A sum command inside a sum command is refused per sub-request: no recursion.
fn nested(group: u32) -> Option<AdsResult> {
    is_sum(group).then_some(AdsResult::INVALID_GROUP)
}

/// The total a reply needs, or 0x705 when it passes the budget.
fn check_budget(
    head_bytes: usize,
    data_lengths: impl Iterator<Item = u32>,
    budget: usize,
) -> Result<(), AdsResult> {
    let mut total = head_bytes;
    for n in data_lengths {
        total = total.saturating_add(n as usize);
    }
    if total > budget {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(())
}

fn read(
    port: &dyn Port,
    group: u32,
    count: u32,
    budget: usize,
    data: &[u8],
) -> Result<Vec<u8>, AdsResult> {
    let (subs, rest) = heads(data, count, 3)?;
    if !rest.is_empty() {
        return Err(AdsResult::INVALID_SIZE);
    }
    let head = if group == READ { 4 } else { 8 };
    check_budget(
        head * subs.len(),
        subs.iter().map(|s| s.read_length),
        budget,
    )?;
    let mut results = Vec::with_capacity(head * subs.len());
    let mut payload = Vec::new();
    for s in &subs {
        let got = match nested(s.group) {
            Some(e) => Err(e),
            None => port.read(s.group, s.offset, s.read_length),
        };
        let (result, mut bytes) = match got {
            Ok(b) => (AdsResult::OK, b),
            Err(e) => (e, Vec::new()),
        };
        bytes.truncate(s.read_length as usize);
        results.extend_from_slice(&result.0.to_le_bytes());
        if group != READ {
            results.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        }
        if group != READ_EX2 {
            // Fixed slots: the data of sub-request k starts where the lengths asked say.
            bytes.resize(s.read_length as usize, 0);
        }
        payload.extend(bytes);
    }
    results.extend(payload);
    Ok(results)
}

fn write(port: &dyn Port, count: u32, budget: usize, data: &[u8]) -> Result<Vec<u8>, AdsResult> {
    let (subs, rest) = heads(data, count, 3)?;
    check_budget(4 * subs.len(), std::iter::empty(), budget)?;
    let total: u64 = subs.iter().map(|s| u64::from(s.read_length)).sum();
    if total != rest.len() as u64 {
        return Err(AdsResult::INVALID_SIZE);
    }
    let mut out = Vec::with_capacity(4 * subs.len());
    let mut at = 0usize;
    for s in &subs {
        let n = s.read_length as usize;
        let bytes = &rest[at..at + n];
        at += n;
        let result = match nested(s.group) {
            Some(e) => e,
            None => match port.write(s.group, s.offset, bytes) {
                Ok(()) => AdsResult::OK,
                Err(e) => e,
            },
        };
        out.extend_from_slice(&result.0.to_le_bytes());
    }
    Ok(out)
}

fn read_write(
    port: &dyn Port,
    count: u32,
    budget: usize,
    data: &[u8],
) -> Result<Vec<u8>, AdsResult> {
    let (subs, rest) = heads(data, count, 4)?;
    check_budget(8 * subs.len(), subs.iter().map(|s| s.read_length), budget)?;
    let total: u64 = subs.iter().map(|s| u64::from(s.write_length)).sum();
    if total != rest.len() as u64 {
        return Err(AdsResult::INVALID_SIZE);
    }
    let mut results = Vec::with_capacity(8 * subs.len());
    let mut payload = Vec::new();
    let mut at = 0usize;
    for s in &subs {
        let n = s.write_length as usize;
        let written = &rest[at..at + n];
        at += n;
        let got = match nested(s.group) {
            Some(e) => Err(e),
            None => port.read_write(s.group, s.offset, s.read_length, written),
        };
        let (result, mut bytes) = match got {
            Ok(b) => (AdsResult::OK, b),
            Err(e) => (e, Vec::new()),
        };
        bytes.truncate(s.read_length as usize);
        results.extend_from_slice(&result.0.to_le_bytes());
        results.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        payload.extend(bytes);
    }
    results.extend(payload);
    Ok(results)
}

/// Bytes of one 0xF085 sub-request: an AddDeviceNotification request with its 16 reserved
/// bytes.
const ADD_NOTIFICATION_BYTES: usize = 40;

/// The sub-request count of a sum command checked, and the reply budget.
fn sum_bounds(count: u32, read_length: u32) -> Result<usize, AdsResult> {
    if count == 0 || count > MAX_SUB_REQUESTS {
        return Err(AdsResult::INVALID_DATA);
    }
    Ok((read_length as usize).min(MAX_REPLY_BYTES))
}

/// Serve 0xF085 (sum add device notification): `add` makes each of the `count` handles
/// written in `data` and gives its result and handle (0 when refused); each sub-request is
/// answered with its own. A malformed request as a whole makes no handle.
pub(crate) fn add_notifications(
    count: u32,
    read_length: u32,
    data: &[u8],
    add: &mut dyn FnMut(NotificationRequest) -> (AdsResult, u32),
) -> Result<Vec<u8>, AdsResult> {
    let budget = sum_bounds(count, read_length)?;
    if data.len() != count as usize * ADD_NOTIFICATION_BYTES {
        return Err(AdsResult::INVALID_SIZE);
    }
    check_budget(8 * count as usize, std::iter::empty(), budget)?;
    let mut out = Vec::with_capacity(8 * count as usize);
    for sub in data.chunks_exact(ADD_NOTIFICATION_BYTES) {
        let mut c = Cursor::new(sub);
        let short = |_| AdsResult::INVALID_SIZE;
        let req = NotificationRequest {
            group: c.u32().map_err(short)?,
            offset: c.u32().map_err(short)?,
            length: c.u32().map_err(short)?,
            mode: c.u32().map_err(short)?,
            max_delay_100ns: c.u32().map_err(short)?,
            cycle_time_100ns: c.u32().map_err(short)?,
        };
        let (result, handle) = match nested(req.group) {
            Some(e) => (e, 0),
            None => add(req),
        };
        out.extend_from_slice(&result.0.to_le_bytes());
        out.extend_from_slice(&handle.to_le_bytes());
    }
    Ok(out)
}

/// Serve 0xF086 (sum delete device notification): `delete` removes each of the `count`
/// handles written in `data` and gives its result.
pub(crate) fn delete_notifications(
    count: u32,
    read_length: u32,
    data: &[u8],
    delete: &mut dyn FnMut(u32) -> AdsResult,
) -> Result<Vec<u8>, AdsResult> {
    let budget = sum_bounds(count, read_length)?;
    if data.len() != count as usize * 4 {
        return Err(AdsResult::INVALID_SIZE);
    }
    check_budget(4 * count as usize, std::iter::empty(), budget)?;
    let mut out = Vec::with_capacity(4 * count as usize);
    for h in data.chunks_exact(4) {
        let handle = u32::from_le_bytes([h[0], h[1], h[2], h[3]]);
        out.extend_from_slice(&delete(handle).0.to_le_bytes());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    /// Group 1 holds 8 bytes 0..8 (read, write); anything else is 0x702.
    struct Memory(RefCell<Vec<u8>>);

    impl Port for Memory {
        fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
            let m = self.0.borrow();
            let (o, n) = (offset as usize, length as usize);
            if group != 1 || o + n > m.len() {
                return Err(AdsResult::INVALID_GROUP);
            }
            Ok(m[o..o + n].to_vec())
        }
        fn write(&self, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult> {
            let mut m = self.0.borrow_mut();
            let o = offset as usize;
            if group != 1 || o + data.len() > m.len() {
                return Err(AdsResult::INVALID_GROUP);
            }
            m[o..o + data.len()].copy_from_slice(data);
            Ok(())
        }
        fn read_write(&self, g: u32, o: u32, n: u32, d: &[u8]) -> Result<Vec<u8>, AdsResult> {
            self.write(g, o, d)?;
            self.read(g, o, n)
        }
    }

    fn words(w: &[u32]) -> Vec<u8> {
        w.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn memory() -> Memory {
        Memory(RefCell::new((0..8).collect()))
    }

    #[test]
    fn read_answers_each_sub_request_in_its_own_slot() {
        let m = memory();
        let req = words(&[1, 2, 2, 9, 0, 3, 1, 6, 2]);
        let r = execute(&m, READ, 3, 100, &req).unwrap();
        assert_eq!(&r[..12], &words(&[0, 0x702, 0])[..]);
        assert_eq!(&r[12..], &[2, 3, 0, 0, 0, 6, 7]);
    }

    #[test]
    fn write_and_read_write_apply_in_order() {
        let m = memory();
        let mut req = words(&[1, 0, 1, 7, 0, 1]);
        req.extend([42, 43]);
        assert_eq!(execute(&m, WRITE, 2, 8, &req).unwrap(), words(&[0, 0x702]));
        let mut req = words(&[1, 1, 2, 1, READ, 0, 4, 0]);
        req.push(9);
        let r = execute(&m, READ_WRITE, 2, 100, &req).unwrap();
        assert_eq!(&r[..16], &words(&[0, 2, 0x702, 0])[..]);
        assert_eq!(&r[16..], &[9, 2], "byte 0 was written by the sum write");
        assert_eq!(m.0.borrow()[0], 42);
    }

    #[test]
    fn malformed_requests_are_one_clear_error() {
        let m = memory();
        assert_eq!(execute(&m, READ, 0, 100, &[]), Err(AdsResult::INVALID_DATA));
        assert_eq!(
            execute(&m, READ, MAX_SUB_REQUESTS + 1, 100, &[]),
            Err(AdsResult::INVALID_DATA)
        );
        assert_eq!(
            execute(&m, READ, 2, 100, &words(&[1, 0, 1])),
            Err(AdsResult::INVALID_SIZE)
        );
        assert_eq!(
            execute(&m, READ, 1, 100, &words(&[1, 0, u32::MAX])),
            Err(AdsResult::INVALID_SIZE),
            "a reply beyond the client's buffer"
        );
        assert_eq!(
            execute(&m, WRITE, 1, 4, &words(&[1, 0, 4])),
            Err(AdsResult::INVALID_SIZE),
            "fewer data bytes than announced"
        );
        assert_eq!(
            execute(&m, ADD_NOTIFICATIONS, 1, 8, &words(&[1, 0, 1])),
            Err(AdsResult::SERVICE_NOT_SUPPORTED)
        );
    }

    #[test]
    fn sum_notifications_answer_each_entry_and_refuse_malformed_requests_whole() {
        let entry = |group: u32| {
            let mut e = words(&[group, 0, 8, 4, 0, 10_000]);
            e.extend([0u8; 16]);
            e
        };
        let data = [entry(0x120101), entry(0x120102)].concat();
        let mut made = Vec::new();
        let mut add = |req: NotificationRequest| {
            made.push(req.group);
            if req.group == 0x120101 {
                (AdsResult::OK, 7)
            } else {
                (AdsResult::ACCESS_DENIED, 0)
            }
        };
        assert_eq!(
            add_notifications(2, 16, &data, &mut add),
            Ok(words(&[0, 7, 0x704, 0]))
        );
        // Malformed as a whole: no entry reaches `add`.
        assert_eq!(
            add_notifications(2, 16, &data[..70], &mut add),
            Err(AdsResult::INVALID_SIZE)
        );
        assert_eq!(
            add_notifications(0, 16, &[], &mut add),
            Err(AdsResult::INVALID_DATA)
        );
        assert_eq!(
            add_notifications(2, 8, &data, &mut add),
            Err(AdsResult::INVALID_SIZE),
            "a reply beyond the client's buffer"
        );
        assert_eq!(made, [0x120101, 0x120102]);
        let mut delete = |h: u32| {
            if h == 7 {
                AdsResult::OK
            } else {
                AdsResult::INVALID_HANDLE
            }
        };
        assert_eq!(
            delete_notifications(2, 8, &words(&[7, 8]), &mut delete),
            Ok(words(&[0, 0x714]))
        );
        assert_eq!(
            delete_notifications(2, 8, &words(&[7]), &mut delete),
            Err(AdsResult::INVALID_SIZE)
        );
    }
}
