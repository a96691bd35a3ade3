//! An ordinary block's words, executed in steps the way grbl's `gc_execute_line` does:
//! 1. collect the words (assignments run in written order, expressions are evaluated),
//! 2. modal changes (G groups, F, S, T, D, M's modal part),
//! 3. the target position (units, zero offset, G92, absolute/incremental),
//! 4. the move or action (dwell, G92, linear, arc),
//! 5. the end of block (H functions, program and subroutine ends).
//!
//! The parser has already refused what a block may not hold (a letter twice, a dwell with
//! company, unknown or unsupported G/M/H numbers), so the steps need not check it again.

use super::block_words::{Words, MAX_FUNCTIONS};
use super::{expr, Interpreter};
use crate::decoder::error::{var_error, DecodeError, Res};
use crate::decoder::frame::FrameKind;
use crate::decoder::io::DecoderIo;
use crate::decoder::line::BlockAt;
use crate::decoder::modal::FeedMode;
use crate::decoder::modal::{apply_g, apply_m, BlockGs, MotionMode, Spindle};
use crate::decoder::note::Note;
use crate::decoder::reader::Reader;
use crate::decoder::vars;
use crate::geometry::arc;
use crate::lang::block::VarRef;
use crate::lang::block::{Item, Value};
use crate::lang::codes;
use crate::lang::eval::Val;
use crate::lang::range::whole_u32 as whole;
use crate::queue::{Action, BlockInfo, Move, MoveKind};
use crate::vocab::axis::slot_of;
use crate::vocab::axis::{Position, AXIS_LETTERS, MAX_AXES};

impl Interpreter {
    pub(in crate::decoder) fn exec_items(
        &mut self,
        items: &[Item],
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        // One `Words` reused from block to block (see `Words::clear`), boxed so taking it
        // out of the decoder moves a pointer.
        let mut w = self.words.take().unwrap_or_default();
        w.clear();
        let r = self.exec_words(items, at, rd, notes, io, &mut w);
        self.words = Some(w);
        r
    }

    /// Steps 1 to 5 over the block's words.
    fn exec_words(
        &mut self,
        items: &[Item],
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
        w: &mut Words,
    ) -> Res {
        for it in items {
            self.collect(it, w)?;
        }
        if items
            .iter()
            .all(|it| matches!(it, Item::Assign { .. } | Item::AssignP { .. }))
        {
            // Assignments only (`P1=12345`): they took effect as they were collected, and
            // there is no modal change, move, function or call, so the steps below would do
            // nothing but queue the block; it is queued directly.
            let info = self.info(rd, at, io);
            self.emit(info, Action::None, false, io);
            return Ok(());
        }
        if w.gs().iter().any(|&(g, _)| g == 160) {
            self.axis_zero_offsets(w, notes)?;
        }
        let gs = self.modal_changes(w)?;
        let info = self.info(rd, at, io);
        // Step 4: the block's move (not yet queued), if it has one.
        let mv = if gs.dwell || gs.set_reference {
            None
        } else if let Some(end) = self.target(w, gs).filter(|&e| !self.stands_without_feed(e)) {
            let mut mv = self.motion(w, end, gs)?;
            self.within_soft_limits(&mv)?;
            mv.path = self.modal.path_mode(gs.contour_this_block);
            Some(mv)
        } else {
            None
        };
        // Step 4½: its technology functions around it (decoder/interp/techno.rs); most
        // blocks have none and go straight on.
        let feed_move = mv.as_ref().is_some_and(|mv| mv.kind != MoveKind::Rapid);
        let mut techno = None;
        if self.techno.concerns(w, feed_move) {
            techno = Some(self.techno.plan(w, feed_move)?).filter(|t| !t.is_empty());
        }
        let (block_nr, line) = (info.n.unwrap_or(0), info.line);
        let mut queued = false;
        if let Some(t) = techno.as_mut() {
            if mv.is_none() && !gs.dwell {
                // A block without motion takes effect, then hands its functions over.
                self.emit(info.clone(), Action::None, false, io);
                queued = true;
            }
            for a in t.actions_before(block_nr, line) {
                self.emit(info.clone(), a, true, io);
            }
        }
        // Step 4 queued: the dwell or the move.
        if gs.dwell {
            // `G04 X2 Y3`: X's time; each further axis is a warning and does not move
            // (TF5200 diagnosis ID 20685, class 1: processing continues).
            for (i, name) in self.settings.axis_names.iter().enumerate() {
                if w.axes_set & (1 << i) != 0 {
                    notes.push(Note::Warning {
                        code: codes::DWELL_EXTRA_AXES,
                        msg: format!(
                            "dwell time programmed with additional axes: {name} does not move"
                        ),
                    });
                }
            }
            let seconds = dwell_seconds(w.dwell_s.unwrap_or(0.0), codes::DWELL_RANGE_G04)?;
            self.emit(info.clone(), Action::Dwell { seconds }, false, io);
            queued = true;
        } else if gs.set_reference {
            self.set_reference(w);
        } else if let Some(mv) = mv {
            self.modal.pos = mv.end;
            self.emit(info.clone(), Action::Move(Box::new(mv)), false, io);
            queued = true;
        }
        if let Some(t) = techno.as_mut() {
            for a in t.actions_after(block_nr, line) {
                self.emit(info.clone(), a, true, io);
            }
        }
        self.end_of_block(w, info, queued, rd, notes, io)
    }

    /// Step 1: one item. Assignments take effect at once, in written order, so a later word
    /// of the block may read them.
    fn collect(&mut self, it: &Item, w: &mut Words) -> Res {
        match it {
            Item::Assign {
                target,
                value,
                col,
                op: None,
            } => self.assign(target, value, *col),
            Item::Assign {
                target,
                value,
                col,
                op: Some(op),
            } => self.combined_assign(target, *op, value, *col),
            Item::AssignP {
                number,
                value,
                col,
                op,
            } => self.assign_p(*number, value, *col, *op),
            Item::GValue { g, value, col } => {
                // G132..G134 weight ramps (no effect here); G04's value is its time.
                let v = match value {
                    Value::Num(n) => *n,
                    Value::Expr(e) => self.eval(e).map_err(|e| e.at(*col))?,
                };
                if *g == 4 {
                    w.dwell_s = Some(v);
                }
                w.push_g(*g, *col).map_err(|e| e.at(*col))
            }
            Item::FunctionValue {
                letter,
                number,
                value,
                col,
            } => {
                let v = match value {
                    Value::Num(n) => *n,
                    Value::Expr(e) => self.eval(e).map_err(|e| e.at(*col))?,
                };
                let n = f64::from(*number);
                if *letter == b'H' {
                    push_function(&mut w.hs, &mut w.h_values, &mut w.n_hs, (n, Some(v)), 'H')
                } else {
                    push_function(&mut w.ms, &mut w.m_values, &mut w.n_ms, (n, Some(v)), 'M')
                }
                .map_err(|e| e.at(*col))
            }
            Item::GCall(c) => {
                self.implicit_call(c.g, c.col, w)?;
                for (k, a) in c.args.iter().enumerate() {
                    if let Some(e) = a {
                        let v = self.eval(e).map_err(|e| e.at(c.col))?;
                        w.call_params.push((k as u32 + 1, v));
                    }
                }
                Ok(())
            }
            Item::NamedAxis(a) => self.collect_named_axis(a, w),
            // An axis's or the spindle's functions: the block's own (one spindle, one set of
            // units).
            Item::Functions(fs) => fs.items.iter().try_for_each(|it| self.collect(it, w)),
            Item::Word(word) => {
                let renamed = self.renamed_slots != 0;
                if let Some(i) = slot_of(word.letter).filter(|_| renamed) {
                    let name = &self.settings.axis_names[i];
                    if self.renamed_slots & (1 << i) != 0 {
                        // The axis in this slot is named `X1` (or `W`): `X` alone names no
                        // axis.
                        let written = if name.is_letter() {
                            String::new()
                        } else {
                            format!(", written {name}=…")
                        };
                        return Err(DecodeError::new(
                            codes::SYNTAX,
                            format!(
                                "axis {} is not configured in this channel (its axis is {name}{written})",
                                word.letter as char
                            ),
                        )
                        .at(word.col));
                    }
                }
                let v = match &word.value {
                    Value::Num(n) => *n,
                    Value::Expr(e) => self.eval(e).map_err(|e| e.at(word.col))?,
                };
                self.collect_word(word.letter, v, word.col, w)
                    .map_err(|e| e.at(word.col))
            }
        }
    }

    /// `P1=…`, `V.L.S=…`, `@P1=…`: at once, in written order. A V. variable or `@P` may take
    /// a string (docs/nc-language.md, "Strings"); P parameters hold numbers.
    fn assign(&mut self, target: &VarRef, value: &crate::lang::block::Expr, col: u32) -> Res {
        if matches!(target, VarRef::ToolData { .. }) {
            // The emulator's tool data come from the tool list at start-up.
            return Err(DecodeError::new(
                codes::UNSUPPORTED,
                format!("{target}: read-only in ncchannel (set it in the tool list)"),
            )
            .at(col));
        }
        if matches!(target, VarRef::ZeroOffset { .. }) {
            let key = crate::lang::eval::resolve(target, &expr::Env(self))
                .map_err(expr::err)
                .map_err(|e| e.at(col))?;
            let v = self.eval(value).map_err(|e| e.at(col))?;
            return self.set_zero_offset(&key, v).map_err(|e| e.at(col));
        }
        if let VarRef::FunctionSync { h, number } = target {
            let n = self.eval(number).map_err(|e| e.at(col))?;
            let v = self.eval(value).map_err(|e| e.at(col))?;
            return self.techno.set_sync(*h, n, v).map_err(|e| e.at(col));
        }
        let key = self.resolve(target).map_err(|e| e.at(col))?;
        if matches!(target, VarRef::P { .. }) {
            let v = self.eval(value).map_err(|e| e.at(col))?;
            return self.set_var(key, v);
        }
        let v = expr::eval_value(value, &expr::Env(self)).map_err(|e| e.at(col))?;
        // A string where numbers are kept, or a number in a STRING variable, is refused at
        // the assignment's column; the store's other refusals as for P.
        match v {
            Val::Num(v) => self.set_var(key, v).map_err(|e| {
                if e.code == codes::EVAL_NUMBER_AS_STRING {
                    e.at(col)
                } else {
                    e
                }
            }),
            Val::Str(s) => self.vars.set_str(key, &s).map_err(|e| {
                let string_fault = matches!(
                    e,
                    vars::VarError::StringTooLong { .. } | vars::VarError::StringToNumber(_)
                );
                let e = var_error(e);
                if string_fault {
                    e.at(col)
                } else {
                    e
                }
            }),
        }
    }

    /// `P<n>=…`, `P<n>+=…` ([`Item::AssignP`]). `P1=12345`, the commonest assignment of a
    /// stream, is stored as written: the general resolver and evaluator (through `dyn Vars`)
    /// give the same slot and value for a finite literal.
    fn assign_p(
        &mut self,
        number: u32,
        value: &crate::lang::block::Expr,
        col: u32,
        op: Option<crate::lang::block::BinOp>,
    ) -> Res {
        use crate::lang::block::{Expr, Index};
        if let (None, Expr::Num(v)) = (op, value) {
            if v.is_finite() {
                return self.set_p(number, *v);
            }
        }
        let target = VarRef::P {
            number: Index::Const(number),
            indices: Vec::new(),
        };
        match op {
            None => self.assign(&target, value, col),
            Some(op) => self.combined_assign(&target, op, value, col),
        }
    }

    /// `P2/=P1`, `P1+=2`: the target's value with the operand by `op`, assigned as `P2=P2/P1`
    /// would be. The operand is a number; `/=` by 0 is the kernel's 20574 (TF5200 diagnosis
    /// ID 20574 "Division by 0.", of "the combined assignment operator /=").
    fn combined_assign(
        &mut self,
        target: &VarRef,
        op: crate::lang::block::BinOp,
        value: &crate::lang::block::Expr,
        col: u32,
    ) -> Res {
        use crate::lang::block::{BinOp, Expr};
        let operand = self.eval(value).map_err(|e| e.at(col))?;
        if op == BinOp::Div && operand == 0.0 {
            return Err(DecodeError::new(
                codes::COMBINED_DIVISION_BY_ZERO,
                "division by 0 in the combined assignment /=",
            )
            .at(col));
        }
        let old = Expr::Var(Box::new(target.clone()));
        let new = Expr::Binary(op, Box::new(old), Box::new(Expr::Num(operand)));
        self.assign(target, &new, col)
    }

    /// `X1=10`: the axis whose configured name it is (resolved at set-up), as its slot's
    /// letter would be.
    fn collect_named_axis(&mut self, a: &crate::lang::block::NamedAxis, w: &mut Words) -> Res {
        let v = match &a.value {
            Value::Num(n) => *n,
            Value::Expr(e) => self.eval(e).map_err(|e| e.at(a.col))?,
        };
        let slot =
            (0..MAX_AXES).find(|&i| self.settings.axes[i] && self.settings.axis_names[i] == a.name);
        let Some(i) = slot else {
            return Err(DecodeError::new(
                codes::SYNTAX,
                format!("axis {} is not configured in this channel", a.name),
            )
            .at(a.col));
        };
        if w.axes_set & (1 << i) != 0 {
            return Err(DecodeError::new(
                codes::AXIS_TWICE,
                format!("axis {} programmed twice in the block", a.name),
            )
            .at(a.col));
        }
        self.collect_word(AXIS_LETTERS[i], v, a.col, w)
            .map_err(|e| e.at(a.col))
    }

    fn collect_word(&mut self, letter: u8, v: f64, col: u32, w: &mut Words) -> Res {
        if !matches!(letter, b'G' | b'M' | b'H') {
            // The parser's range check, again for values computed from expressions.
            crate::lang::range::word_value(letter, v)
                .map_err(|e| DecodeError::new(e.code, e.message))?;
        }
        match letter {
            // The parser takes G, M and H as literal whole numbers only.
            b'G' => w.push_g(whole(v).unwrap_or(u32::MAX), col)?,
            b'M' => push_function(&mut w.ms, &mut w.m_values, &mut w.n_ms, (v, None), 'M')?,
            b'H' => push_function(&mut w.hs, &mut w.h_values, &mut w.n_hs, (v, None), 'H')?,
            b'F' => w.feed = Some((v, col)),
            b'S' => w.spindle_rpm = Some(v),
            // Whole numbers: the range check above refused anything else.
            b'T' => {
                w.tool = whole(v);
                w.tool_col = col;
            }
            b'D' => w.tool_offset = whole(v).map(|d| (d, col)),
            b'I' => w.ijk[0] = Some(v),
            b'J' => w.ijk[1] = Some(v),
            b'K' => w.ijk[2] = Some(v),
            b'R' => w.radius = Some(v),
            letter => {
                let slot = match slot_of(letter) {
                    Some(i) => Some(i),
                    None => self.lettered_slot(letter)?,
                };
                if let Some(i) = slot {
                    if self.settings.axes[i] && w.axes_set & (1 << i) != 0 {
                        // `X1=5` and `X5` both name the slot of axis X1 (the parser sees
                        // only letters twice).
                        return Err(DecodeError::new(
                            codes::AXIS_TWICE,
                            format!("axis {} programmed twice in the block", letter as char),
                        ));
                    }
                    if !self.settings.axes[i] {
                        if letter != b'X' {
                            return Err(unconfigured(letter));
                        }
                        w.unconfigured_x_col = Some(col);
                    }
                    w.axes[i] = v;
                    w.axes_set |= 1 << i;
                }
                // E: accepted, no effect in the emulator.
            }
        }
        Ok(())
    }

    /// Step 2: G groups, then F (in the feed mode just set), S, T, D and the M functions'
    /// modal part (spindle, coolant).
    fn modal_changes(&mut self, w: &mut Words) -> Res<BlockGs> {
        let mut gs = BlockGs::default();
        let mut call = None;
        let mut trc_selected = false;
        for &(g, col) in w.gs() {
            if matches!(g, 41 | 42) {
                // `G41 X10 Y20 G42`: TF5200 diagnosis ID 20114 "Double programmed selection
                // of tool radius compensation.".
                if std::mem::replace(&mut trc_selected, true) {
                    return Err(DecodeError::new(
                        codes::TRC_TWICE,
                        format!("G{g}: tool radius compensation selected twice in the block"),
                    )
                    .at(col));
                }
            }
            if g == 160 {
                // `G160=n` without axes: the warning was given ([`Self::axis_zero_offsets`]).
                continue;
            }
            if !apply_g(&mut self.modal, g, &mut gs) {
                if crate::lang::gcall::G_CALLS.contains(&g) {
                    if call.replace((g, col)).is_some() {
                        return Err(two_calls().at(col));
                    }
                    continue;
                }
                return Err(
                    DecodeError::new(codes::UNKNOWN_G, format!("unknown G function G{g}")).at(col),
                );
            }
        }
        if let Some((g, col)) = call {
            self.implicit_call(g, col, w)?;
        }
        if gs.axis_weights {
            // G130 X70: weightings, no move (the weighting itself is not modelled).
            w.axes_set = 0;
        }
        if gs.dwell {
            // `G04 X<t>` / `G04 F<t>`: the word is the time, not an axis or a feed. The
            // parser refused a lettered axis without X; a named one (`Y1=2`) is known only
            // here (TF5200 diagnosis ID 20014). Further axes stay in `axes_set` for the
            // warning 20685 and do not move.
            if w.axes_set != 0 && w.axes_set & 1 == 0 {
                return Err(DecodeError::new(
                    codes::DWELL_NOT_FIRST_AXIS,
                    "dwell time not programmed with the coordinate of the first main axis",
                ));
            }
            if w.axes_set & 1 != 0 {
                w.axes_set &= !1;
                w.dwell_s = Some(w.axes[0]);
            } else if let Some((f, _)) = w.feed.take() {
                w.dwell_s = Some(f);
            } else if let Some(revolutions) = w.spindle_rpm.take() {
                // `G04 S<n>`: n revolutions of the main spindle at its programmed speed, not
                // a new speed (TF5200 programming manual, "Dwell time (G04), (#TIME)").
                w.dwell_s = Some(self.revolutions_s(revolutions)?);
            }
        }
        if let Some((f, _)) = w.feed {
            let mm = f * self.modal.units.mm_per_unit();
            match self.modal.feed_mode {
                FeedMode::PerMinute => self.modal.feed_mm_per_min = mm,
                FeedMode::PerRevolution => self.modal.feed_mm_per_rev = mm,
            }
        }
        if let Some(s) = w.spindle_rpm {
            self.modal.spindle_rpm = s;
        }
        if let Some(t) = w.tool {
            self.modal.tool = t;
        }
        // einrechnen_mit_t (P-CHAN-00014): `T80` is `T80 D80`; a D in the block wins.
        let d = w
            .tool_offset
            .or(w.tool.filter(|_| self.t_selects_d).map(|t| (t, w.tool_col)));
        if let Some((d, col)) = d {
            self.select_tool_data(d).map_err(|e| e.at(col))?;
        }
        for &m in w.ms() {
            apply_m(&mut self.modal, m);
        }
        if let Some(col) = w.unconfigured_x_col.filter(|_| w.axes_set & 1 != 0) {
            return Err(unconfigured(b'X').at(col));
        }
        Ok(gs)
    }

    /// The time of `revolutions` turns of the main spindle at the programmed speed, s. A
    /// spindle that does not turn (M05, or no S programmed) never completes them: refused as
    /// a dwell time out of range (20752), since no kernel id names it.
    fn revolutions_s(&self, revolutions: f64) -> Res<f64> {
        let rpm = self.modal.spindle_rpm;
        if self.modal.spindle == Spindle::Off || rpm <= 0.0 {
            return Err(DecodeError::new(
                codes::DWELL_RANGE_G04,
                format!(
                    "dwell of {revolutions} spindle revolutions with the spindle not turning \
                     (speed {rpm} rpm, M03 or M04 with an S needed)"
                ),
            ));
        }
        Ok(revolutions * 60.0 / rpm)
    }

    /// `D<d>`: select tool data set `d`. A data set the list marks invalid (`wz[d].gueltig 0`,
    /// P-TOOL-00005) is refused with 900140: the kernel's error list in this repository has no
    /// id of its own for it, and 900140 is what G41/G42 without usable tool data answers.
    fn select_tool_data(&mut self, d: u32) -> Res {
        if self.tool(Some(d)).is_some_and(|t| !t.valid) {
            return Err(DecodeError::new(
                codes::TRC_IMPOSSIBLE,
                format!("D{d}: tool data set {d} is not valid (wz[{d}].gueltig 0, P-TOOL-00005)"),
            ));
        }
        self.modal.tool_offset = d;
        Ok(())
    }

    /// The offset from program to machine coordinates of axis `i`: zero offset and G92 (none
    /// under G53 in this block), plus the active D's tool length on the tool axis (Z under
    /// G17, Y under G18, X under G19; TF5200 "#TLAX": "+" orientation) and its axis offsets
    /// (P-TOOL-00006). Like the kernel's default (P-CHAN-00100 `move_tool_offsets_directly`
    /// 0), a new D takes effect at an axis' next absolute position.
    pub(super) fn program_offset(&self, gs: BlockGs) -> [f64; MAX_AXES] {
        let mut off = if gs.machine_coords {
            [0.0; MAX_AXES]
        } else {
            self.modal.g92_offset
        };
        if self.modal.zero_offset > 0 && !gs.machine_coords {
            let zero = self.zero_offsets[self.modal.zero_offset - 1];
            for (o, z) in off.iter_mut().zip(zero) {
                *o += z;
            }
        }
        if let Some(t) = self.tool(None).filter(|t| t.valid) {
            for (o, a) in off.iter_mut().zip(t.axis_offsets_mm) {
                *o += a;
            }
            let tool_axis = match self.modal.plane {
                crate::queue::Plane::Xy => 2,
                crate::queue::Plane::Zx => 1,
                crate::queue::Plane::Yz => 0,
            };
            off[tool_axis] += t.length_mm;
        }
        off
    }

    /// Step 3: the block's end point in machine coordinates, if it programs an axis.
    fn target(&self, w: &Words, gs: BlockGs) -> Option<Position> {
        if w.axes_set == 0 {
            return None;
        }
        let start = self.modal.pos;
        let offset = self.program_offset(gs);
        let mut end = start;
        for (i, &v) in w.axes.iter().enumerate() {
            if w.axes_set & (1 << i) != 0 {
                let v = v * self.length_scale(i);
                end[i] = if self.modal.absolute {
                    v + offset[i]
                } else {
                    start[i] + v
                };
            }
        }
        Some(end)
    }

    /// mm per programmed unit on axis `i`: inch scales the linear axes, not A, B, C.
    pub(super) fn length_scale(&self, i: usize) -> f64 {
        match AXIS_LETTERS[i] {
            b'A' | b'B' | b'C' => 1.0,
            _ => self.modal.units.mm_per_unit(),
        }
    }

    /// G92: the programmed axis values become the current position in program coordinates.
    fn set_reference(&mut self, w: &Words) {
        let zero = self.program_offset(BlockGs::default());
        for (i, &v) in w.axes.iter().enumerate() {
            if w.axes_set & (1 << i) != 0 {
                let here = self.modal.pos[i] - (zero[i] - self.modal.g92_offset[i]);
                self.modal.g92_offset[i] = here - v * self.length_scale(i);
            }
        }
    }

    /// A G01 block that ends where it starts while no feed is programmed: it does not move,
    /// so it is no motion block and needs no F (TF5200 diagnosis ID 20008 "Feed rate in
    /// motion block is 0." is of a block that moves; the local subroutine example of ID
    /// 21500 runs `N010 X0 Y0 Z0` at program start without one).
    fn stands_without_feed(&self, end: Position) -> bool {
        self.modal.motion == MotionMode::Linear
            && end == self.modal.pos
            && self.path_feed().is_err()
    }

    /// The path feed for G1/G2/G3, mm/min: F under G94, F × S under G95.
    fn path_feed(&self) -> Res<f64> {
        let feed = match self.modal.feed_mode {
            FeedMode::PerMinute => self.modal.feed_mm_per_min,
            FeedMode::PerRevolution => {
                if self.modal.spindle_rpm <= 0.0 {
                    return Err(DecodeError::new(
                        codes::NO_FEED,
                        "G95 feed per revolution needs a spindle speed (S)",
                    ));
                }
                self.modal.feed_mm_per_rev * self.modal.spindle_rpm
            }
        };
        if feed <= 0.0 {
            return Err(DecodeError::new(
                codes::NO_FEED,
                "no feed programmed (F) for G1/G2/G3",
            ));
        }
        Ok(feed)
    }

    /// Step 4: the move from the last programmed position to `end`.
    fn motion(&self, w: &Words, end: Position, gs: BlockGs) -> Res<Move> {
        let start = self.modal.pos;
        let m = self.modal.motion;
        if m == MotionMode::Rapid {
            return Ok(Move {
                kind: MoveKind::Rapid,
                start,
                end,
                feed_mm_per_min: 0.0,
                path: Default::default(),
            });
        }
        let feed = self.path_feed()?;
        if m == MotionMode::Linear {
            return Ok(Move {
                kind: MoveKind::Line,
                start,
                end,
                feed_mm_per_min: feed,
                path: Default::default(),
            });
        }
        let unit = self.modal.units.mm_per_unit();
        let scaled = |v: Option<f64>| v.map(|v| v * unit);
        let mut ijk = w.ijk.map(scaled);
        if self.modal.centre_absolute {
            // G161: the centre in program coordinates, made the offset from the start point
            // the arc takes (TF5200 programming manual, "Specifying centre point for circle
            // definition (G161/G162)").
            let offset = self.program_offset(gs);
            for (k, c) in ijk.iter_mut().enumerate() {
                if let Some(c) = c {
                    *c += offset[k] - start[k];
                }
            }
        }
        arc::arc_move(
            &arc::ArcSpec {
                plane: self.modal.plane,
                ijk,
                radius: scaled(w.radius),
                cw: m == MotionMode::ArcCw,
            },
            start,
            end,
            feed,
            self.settings.arc_tolerance_mm,
        )
        .map_err(|e| DecodeError::new(e.code(), e.to_string()))
    }

    /// Software limits: every axis's end point, and for an arc every point of the arc in
    /// its plane, inside `[min, max]` of runtime.toml, or the block is refused before any
    /// of it moves — as a real kernel checks set positions in path preparation. An axis that
    /// starts outside may move back inside ([`arc::outside_limits`]).
    fn within_soft_limits(&self, mv: &Move) -> Res {
        let Some(b) = arc::outside_limits(mv, &self.settings.soft_limits_mm, &self.settings.axes)
        else {
            return Ok(());
        };
        let reach = if matches!(mv.kind, MoveKind::Arc { .. }) && !b.at_end {
            "arc reaches"
        } else {
            "end point"
        };
        Err(DecodeError::new(codes::SOFT_LIMIT, b.message(reach)))
    }

    /// Step 5: H functions are reported; M17/M29 return, M2/M30 end the program; a block
    /// that queued nothing yet is queued as a block without motion.
    fn end_of_block(
        &mut self,
        w: &Words,
        info: BlockInfo,
        queued: bool,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let stop = w.ms().iter().copied().find(|m| matches!(m, 0 | 1));
        let queued = match stop {
            Some(m) => {
                if !queued {
                    self.emit(info.clone(), Action::None, false, io);
                }
                let optional = m == 1;
                self.emit(info.clone(), Action::Stop { optional }, true, io);
                true
            }
            None => queued,
        };
        let end_m = w
            .ms()
            .iter()
            .copied()
            .find(|m| matches!(m, 2 | 30 | 17 | 29));
        if let Some(m @ (17 | 29)) = end_m {
            if rd.top().kind() == FrameKind::Main {
                return Err(DecodeError::new(
                    codes::UNEXPECTED_SUB_END,
                    format!("unexpected M{m} in main program"),
                ));
            }
        }
        if let Some((g, col)) = w.call {
            if self.m6_subroutine(w).is_some() {
                return Err(DecodeError::new(
                    codes::UNSUPPORTED,
                    "G800–G819 and M6 with its subroutine in one block",
                )
                .at(col));
            }
            if !queued {
                self.emit(info.clone(), Action::None, false, io);
            }
            return self.call_g800(g, &w.call_params, end_m.map(|m| (m, info)), rd, notes, io);
        }
        if let Some(name) = self.m6_subroutine(w) {
            if !queued {
                self.emit(info.clone(), Action::None, false, io);
            }
            return self.call_m6(&name, end_m, info, rd, notes, io);
        }
        if let Some(17 | 29) = end_m {
            if !queued {
                self.emit(info, Action::None, false, io);
            }
            rd.top().flow().warn_open_flow(notes);
            self.return_from_subroutine(rd, notes);
            return self.resume_held_end(rd, notes, io);
        }
        let Some(m) = end_m else {
            if !queued {
                self.emit(info, Action::None, false, io);
            }
            return Ok(());
        };
        self.program_end_checks(m, rd, notes)?;
        if !queued {
            self.emit(info.clone(), Action::None, false, io);
        }
        self.program_end(m, info, rd, notes, io)
    }

    /// G800–G819 in this block (`col` its column): its subroutine must be configured
    /// (20131 otherwise, as the kernel's P-CHAN-00187 says), one call per block.
    fn implicit_call(&self, g: u32, col: u32, w: &mut Words) -> Res {
        if self.g800_subroutine(g).is_none() {
            return Err(DecodeError::new(
                codes::UNKNOWN_G,
                format!(
                    "unknown G function G{g}: no g800_prog_file[{}] in the channel list",
                    g - 800
                ),
            )
            .at(col));
        }
        if w.call.is_some() {
            return Err(two_calls().at(col));
        }
        w.call = Some((g, col));
        w.call_params.clear();
        Ok(())
    }

    /// M2/M30: a block search that reaches it failed; in a subroutine it is a warning; in
    /// the main program every control block must be closed.
    pub(super) fn program_end_checks(
        &mut self,
        m: u32,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
    ) -> Res {
        if let Some(s) = self.search {
            return Err(DecodeError::new(
                codes::SEARCH_NOT_FOUND,
                format!("block search target {} not found", s.target),
            ));
        }
        if rd.top().kind() != FrameKind::Main {
            notes.push(Note::Warning {
                code: codes::UNEXPECTED_PROGRAM_END,
                msg: format!("M{m} in a subroutine: the program ends"),
            });
            Ok(())
        } else {
            rd.top().flow().warn_open_flow(notes);
            Ok(())
        }
    }
}

fn two_calls() -> DecodeError {
    DecodeError::new(
        codes::UNSUPPORTED,
        "two implicit subroutine calls (G800–G819) in one block",
    )
}

impl Interpreter {
    /// `G160=n`: without an axis in the block the kernel's warning 20003 (TF5200 diagnosis ID
    /// 20003, "programmed G function only useful with an axis", class 1: the program goes
    /// on) and nothing else; with axes the axis-specific zero offsets, which ncchannel does
    /// not model (900133).
    #[cold]
    fn axis_zero_offsets(&self, w: &Words, notes: &mut Vec<Note>) -> Res {
        let col = w
            .gs()
            .iter()
            .find(|&&(g, _)| g == 160)
            .map_or(1, |&(_, c)| c);
        if w.axes_set != 0 {
            return Err(DecodeError::new(
                codes::UNSUPPORTED,
                "G160 (axis-specific zero offsets) is not supported by ncchannel",
            )
            .at(col));
        }
        notes.push(Note::Warning {
            code: codes::G_WITHOUT_AXIS,
            msg: format!("G160 without an axis has no effect (column {col})"),
        });
        Ok(())
    }

    /// The slot of the configured axis named by the one letter `letter` outside X Y Z A B C
    /// (`W10` where the channel list names an axis `W`): `Some(None)` for a letter that is no
    /// axis word (E), an error for an axis letter the channel does not configure (U V W).
    #[cold]
    fn lettered_slot(&self, letter: u8) -> Result<Option<usize>, DecodeError> {
        let slot = (0..MAX_AXES).find(|&i| {
            let n = &self.settings.axis_names[i];
            self.settings.axes[i] && n.is_letter() && n.letter() == letter
        });
        match slot {
            Some(i) => Ok(Some(i)),
            None if matches!(letter, b'U' | b'V' | b'W') => Err(unconfigured(letter)),
            None => Ok(None),
        }
    }
}

fn unconfigured(letter: u8) -> DecodeError {
    DecodeError::new(
        codes::SYNTAX,
        format!("axis {} is not configured in this channel", letter as char),
    )
}

/// Add an M or H number, and its value if programmed with one, to the block's list (at most
/// [`MAX_FUNCTIONS`]).
fn push_function(
    list: &mut [u32; MAX_FUNCTIONS],
    values: &mut [Option<f64>; MAX_FUNCTIONS],
    n: &mut usize,
    (v, value): (f64, Option<f64>),
    letter: char,
) -> Res {
    if *n == list.len() {
        return Err(DecodeError::new(
            codes::SYNTAX,
            format!("too many {letter} functions in one block"),
        ));
    }
    // The parser admits only whole numbers 0..=65535 for M and H, and refuses the same M
    // twice in one scope (20765).
    let number = whole(v).unwrap_or(0);
    list[*n] = number;
    values[*n] = value;
    *n += 1;
    Ok(())
}

/// A programmed dwell time, s: refused when negative (`code`: 20752 after G04, 20751 after
/// `#TIME`), as `ncchannel check` refuses a literal one (`crate::lang::range::dwell_time`).
pub(super) fn dwell_seconds(seconds: f64, code: u32) -> Result<f64, DecodeError> {
    crate::lang::range::dwell_time(seconds, code).map_err(|e| DecodeError::new(e.code, e.message))
}
