//! The streamed program of a soak: an endless supply of N-numbered NC lines — moves and arcs
//! inside a box well within the axis limits, parameter blocks, M functions, optionally
//! subroutine calls and cache operations — so a 10-million-block run needs no 10-million-line
//! file. Each epoch (stream start after a reset) numbers its lines N1, N2, … so the checker
//! knows which block must come next.

use std::fmt::Write as _;

use serde::Deserialize;

use super::rng::SplitMix64;

/// The longest line the generator writes, CR LF included; packets hold at least one.
pub const MAX_LINE_BYTES: usize = 96;

/// The mix and geometry of a generated program (scenario `[program]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProgramSpec {
    /// Relative weights of the line kinds.
    pub moves: u32,
    pub arcs: u32,
    pub params: u32,
    pub(crate) m_functions: u32,
    /// `L name` calls of the `subroutines` (files on the channel's search path).
    pub calls: u32,
    /// `#CACHE LOAD/CLEAR[FILE=…]` of the `cache_files`.
    pub cache_ops: u32,
    /// Largest step of a move per axis, mm.
    pub(crate) step_mm: f64,
    /// Feed range, mm/min.
    pub feed_mm_per_min: [f64; 2],
    /// Moves stay within ±box_mm of the origin on X and Y.
    pub(crate) box_mm: f64,
    pub subroutines: Vec<String>,
    pub(crate) cache_files: Vec<String>,
    /// Cache entries the program may hold at once (the channel's max_cache_number): a
    /// `#CACHE LOAD` beyond it would be error 21562, so the generator clears one first.
    pub(crate) cache_slots: u32,
}

impl Default for ProgramSpec {
    fn default() -> Self {
        ProgramSpec {
            moves: 6,
            arcs: 1,
            params: 2,
            m_functions: 1,
            calls: 0,
            cache_ops: 0,
            step_mm: 0.05,
            feed_mm_per_min: [6000.0, 30000.0],
            box_mm: 200.0,
            subroutines: Vec::new(),
            cache_files: Vec::new(),
            cache_slots: 2,
        }
    }
}

impl ProgramSpec {
    /// Why this spec cannot generate, if it cannot.
    pub fn check(&self) -> Result<(), String> {
        let w = [
            self.moves,
            self.arcs,
            self.params,
            self.m_functions,
            self.calls,
            self.cache_ops,
        ];
        if w.iter().all(|&x| x == 0) {
            return Err("[program]: all line weights are 0".into());
        }
        if !(self.step_mm.is_finite() && self.step_mm > 0.0 && self.step_mm <= 100.0) {
            return Err("[program] step_mm must be in (0, 100]".into());
        }
        let [f0, f1] = self.feed_mm_per_min;
        if !(f0.is_finite() && f1.is_finite() && f0 > 0.0 && f0 <= f1 && f1 <= 1e6) {
            return Err(
                "[program] feed_mm_per_min must be [low, high] with 0 < low <= high".into(),
            );
        }
        if !(self.box_mm.is_finite() && self.box_mm >= 4.0 * self.step_mm && self.box_mm <= 1e5) {
            return Err("[program] box_mm must be at least 4 × step_mm".into());
        }
        if self.calls > 0 && self.subroutines.is_empty() {
            return Err("[program] calls > 0 needs subroutines = [\"name\", …]".into());
        }
        if self.cache_ops > 0 && self.cache_slots == 0 {
            return Err("[program] cache_ops > 0 needs cache_slots >= 1".into());
        }
        if self.cache_ops > 0 && self.cache_files.is_empty() {
            return Err("[program] cache_ops > 0 needs cache_files = [\"name\", …]".into());
        }
        for name in self.subroutines.iter().chain(&self.cache_files) {
            let ok = !name.is_empty()
                && name.len() <= 32
                && name
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b"._-".contains(&b));
            if !ok {
                return Err(format!(
                    "[program] file name '{name}': 1 to 32 characters of letters, digits, . _ -"
                ));
            }
        }
        Ok(())
    }
}

/// The endless program of one channel.
#[derive(Debug, Clone)]
pub struct Generator {
    spec: ProgramSpec,
    rng: SplitMix64,
    /// N of the next line (from 1 each epoch).
    next_n: u32,
    /// Where the last generated motion ends, X and Y, mm.
    x_mm: f64,
    y_mm: f64,
    /// The machine may not be where the model says (after a reset or a subroutine call): the
    /// next motion is an absolute line, never an arc whose centre depends on the start.
    position_unknown: bool,
    /// Bit k: P<k> was assigned this epoch (a reset forgets parameters; reading an unset one
    /// is error `codes::EVAL_UNDEFINED`).
    params_set: u16,
    /// Indices into `cache_files` loaded this epoch (a reset clears the cache).
    cached: Vec<usize>,
    /// The line being written, kept between lines for its capacity.
    line: String,
}

impl Generator {
    /// `spec` must have passed [`ProgramSpec::check`].
    pub fn new(spec: ProgramSpec, rng: SplitMix64) -> Self {
        Generator {
            spec,
            rng,
            next_n: 1,
            x_mm: 0.0,
            y_mm: 0.0,
            position_unknown: true,
            params_set: 0,
            cached: Vec::new(),
            line: String::with_capacity(MAX_LINE_BYTES),
        }
    }

    /// A new stream starts (program start after a reset): numbering from N1, preamble first.
    pub(crate) fn new_epoch(&mut self) {
        self.next_n = 1;
        self.position_unknown = true;
        self.params_set = 0;
        self.cached.clear();
    }

    fn feed(&mut self) -> u32 {
        let [lo, hi] = self.spec.feed_mm_per_min;
        self.rng.range_f64(lo, hi).round().max(1.0) as u32
    }

    fn step_axis(&mut self, v: f64) -> f64 {
        let s = self.spec.step_mm;
        let limit = self.spec.box_mm - 2.0 * s;
        let mut n = v + self.rng.range_f64(-s, s);
        // Reflect at the box so the walk never leaves it.
        if n > limit {
            n = limit - (n - limit);
        } else if n < -limit {
            n = -limit + (-limit - n);
        }
        (n * 1000.0).round() / 1000.0
    }

    /// Append the next line (CR LF ended) to `out`; returns its N.
    pub(crate) fn next_line(&mut self, out: &mut Vec<u8>) -> u32 {
        let n = self.next_n;
        self.next_n = self.next_n.wrapping_add(1).max(1);
        let mut s = std::mem::take(&mut self.line);
        s.clear();
        if n == 1 {
            let f = self.feed();
            let _ = write!(s, "N{n} G90 G17 G01 F{f}");
        } else {
            let kind = self
                .rng
                .weighted(&[
                    self.spec.moves,
                    self.spec.arcs,
                    self.spec.params,
                    self.spec.m_functions,
                    self.spec.calls,
                    self.spec.cache_ops,
                ])
                .unwrap_or(0);
            match kind {
                1 if !self.position_unknown => self.arc(&mut s, n),
                0 | 1 => self.line(&mut s, n),
                2 => {
                    let k = self.rng.range(1, 9);
                    if self.params_set & (1 << k) == 0 || self.rng.chance(0.5) {
                        self.params_set |= 1 << k;
                        let v = self.rng.range(0, 99_999) as f64 / 1000.0;
                        push_n(&mut s, n);
                        s.push_str(" P");
                        push_u64(&mut s, k);
                        s.push('=');
                        push_thousandths(&mut s, v);
                    } else {
                        push_n(&mut s, n);
                        s.push_str(" P");
                        push_u64(&mut s, k);
                        s.push_str("=P");
                        push_u64(&mut s, k);
                        s.push_str("+1 (count)");
                    }
                }
                3 => {
                    let m = if self.rng.chance(0.5) { 8 } else { 9 };
                    push_n(&mut s, n);
                    s.push_str(if m == 8 { " M08" } else { " M09" });
                }
                4 => {
                    let i = self.rng.range(0, self.spec.subroutines.len() as u64 - 1) as usize;
                    let name = &self.spec.subroutines[i];
                    if name.ends_with(".cyc") {
                        // A cycle takes its parameters @P1, @P2 (0.05 ... 0.5 mm).
                        let a = self.rng.range(50, 500) as f64 / 1000.0;
                        let b = self.rng.range(50, 500) as f64 / 1000.0;
                        push_n(&mut s, n);
                        s.push_str(" L CYCLE [NAME=");
                        s.push_str(name);
                        s.push_str(" @P1=");
                        push_thousandths(&mut s, a);
                        s.push_str(" @P2=");
                        push_thousandths(&mut s, b);
                        s.push(']');
                    } else {
                        let _ = write!(s, "N{n} L {name}");
                    }
                    self.position_unknown = true;
                }
                _ => {
                    let mut i = self.rng.range(0, self.spec.cache_files.len() as u64 - 1) as usize;
                    let loaded = self.cached.iter().position(|&c| c == i);
                    let full = self.cached.len() >= self.spec.cache_slots as usize;
                    // Load (or refresh) what fits; when full, clear an entry first.
                    let op = match loaded {
                        Some(k) if self.rng.chance(0.5) => {
                            self.cached.swap_remove(k);
                            "CLEAR"
                        }
                        Some(_) => "LOAD",
                        None if !full => {
                            self.cached.push(i);
                            "LOAD"
                        }
                        None => {
                            let k = self.rng.range(0, self.cached.len() as u64 - 1) as usize;
                            i = self.cached.swap_remove(k);
                            "CLEAR"
                        }
                    };
                    let _ = write!(s, "N{n} #CACHE {op}[FILE={}]", self.spec.cache_files[i]);
                }
            }
        }
        s.truncate(MAX_LINE_BYTES - 2);
        out.extend_from_slice(s.as_bytes());
        out.extend_from_slice(b"\r\n");
        self.line = s;
        n
    }

    fn line(&mut self, s: &mut String, n: u32) {
        self.x_mm = self.step_axis(self.x_mm);
        self.y_mm = self.step_axis(self.y_mm);
        push_n(s, n);
        s.push_str(" G01 X");
        push_thousandths(s, self.x_mm);
        s.push_str(" Y");
        push_thousandths(s, self.y_mm);
        if self.rng.chance(0.2) {
            let f = self.feed();
            s.push_str(" F");
            push_u64(s, f);
        }
        self.position_unknown = false;
    }

    /// A half circle along X: from (x, y) to (x ± 2r, y), centre (x ± r, y). It bulges r off
    /// the chord, which the box margin of 2 × step_mm covers.
    fn arc(&mut self, s: &mut String, n: u32) {
        let r = ((self.rng.range_f64(0.2, 0.5) * self.spec.step_mm) * 1000.0).round() / 1000.0;
        let r = r.max(0.001);
        let limit = self.spec.box_mm - 2.0 * self.spec.step_mm;
        let room_right = self.x_mm + 2.0 * r <= limit;
        let room_left = self.x_mm - 2.0 * r >= -limit;
        let dir = if !room_right || (room_left && self.rng.chance(0.5)) {
            -1.0
        } else {
            1.0
        };
        let g = if self.rng.chance(0.5) { 2 } else { 3 };
        self.x_mm = ((self.x_mm + dir * 2.0 * r) * 1000.0).round() / 1000.0;
        push_n(s, n);
        s.push_str(if g == 2 { " G02 X" } else { " G03 X" });
        push_thousandths(s, self.x_mm);
        s.push_str(" Y");
        push_thousandths(s, self.y_mm);
        s.push_str(" I");
        push_thousandths(s, dir * r);
        s.push_str(" J0");
    }
}

/// `N<n>`, the line's block number.
fn push_n(s: &mut String, n: u32) {
    s.push('N');
    push_u64(s, u64::from(n));
}

/// An integer in decimal, through `itoa` rather than the `fmt` machinery: formatting the
/// generated lines with `write!` was a sixth of the work of `bench --load cycle`'s ticks.
fn push_u64(s: &mut String, v: impl Into<u64>) {
    s.push_str(itoa::Buffer::new().format(v.into()));
}

/// A value of whole thousandths (every number the generator draws is one) as `{:.3}` writes
/// it, through the integer path.
fn push_thousandths(s: &mut String, v: f64) {
    // Within ±2^53 / 1000 the nearest integer is exact; `{:.3}` prints -0.0 as "-0.000".
    let m = (v * 1000.0).round();
    if !m.is_finite() || m.abs() >= 9.0e15 {
        let _ = write!(s, "{v:.3}");
        return;
    }
    let k = m.abs() as u64;
    if v.is_sign_negative() {
        s.push('-');
    }
    push_u64(s, k / 1000);
    let frac = k % 1000;
    s.push('.');
    s.push(char::from(b'0' + (frac / 100) as u8));
    s.push(char::from(b'0' + (frac / 10 % 10) as u8));
    s.push(char::from(b'0' + (frac % 10) as u8));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_numbered_bounded_and_restart_per_epoch() {
        let spec = ProgramSpec {
            calls: 1,
            cache_ops: 1,
            subroutines: vec!["Global.sub".into()],
            cache_files: vec!["Macro.cyc".into()],
            ..ProgramSpec::default()
        };
        spec.check().unwrap();
        let mut g = Generator::new(spec, SplitMix64::new(1));
        let mut out = Vec::new();
        for i in 1..=5000u32 {
            out.clear();
            assert_eq!(g.next_line(&mut out), i);
            assert!(out.len() <= MAX_LINE_BYTES && out.ends_with(b"\r\n"));
            let text = std::str::from_utf8(&out).unwrap();
            assert!(text.starts_with(&format!("N{i} ")), "{text}");
        }
        g.new_epoch();
        out.clear();
        assert_eq!(g.next_line(&mut out), 1);
        assert!(out.starts_with(b"N1 G90"));
    }

    #[test]
    fn bad_specs_are_refused() {
        let zero = ProgramSpec {
            moves: 0,
            arcs: 0,
            params: 0,
            m_functions: 0,
            ..ProgramSpec::default()
        };
        assert!(zero.check().is_err());
        let calls = ProgramSpec {
            calls: 1,
            ..ProgramSpec::default()
        };
        assert!(calls.check().is_err());
    }

    /// The integer path writes exactly what `{:.3}` writes for whole thousandths, signs and
    /// -0.0 included.
    #[test]
    fn thousandths_write_as_the_float_formatter_does() {
        let mut rng = SplitMix64::new(7);
        let mut values = vec![0.0, -0.0, 0.001, -0.001, 0.5, -0.5, 199.9, -199.9, 99.999];
        for _ in 0..100_000 {
            let k = rng.range(0, 400_000) as f64 - 200_000.0;
            values.push(k / 1000.0);
            values.push(((k / 997.0) * 1000.0).round() / 1000.0);
        }
        for v in values {
            let mut s = String::new();
            push_thousandths(&mut s, v);
            assert_eq!(s, format!("{v:.3}"), "{v:?}");
        }
    }
}
