//! An ordinary block's words, executed in steps the way grbl's `gc_execute_line` does:
//! collect the words → modal changes → target position → the move or action → end of block.

use super::*;

impl Decoder {
    pub(super) fn exec_items(
        &mut self,
        items: &[Item],
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let mut gs = BlockGs::default();
        let mut axes: [Option<f64>; MAX_AXES] = [None; MAX_AXES];
        let mut ijk: [Option<f64>; 3] = [None; 3];
        let mut radius: Option<f64> = None;
        let mut ms: [u32; 8] = [0; 8];
        let mut n_ms = 0usize;
        for it in items {
            match it {
                Item::Assign { target, value, col } => {
                    let key = self.resolve(target).map_err(|e| e.at(*col))?;
                    let v = self.eval(value).map_err(|e| e.at(*col))?;
                    self.set_var(key, v)?;
                }
                Item::GValue { g, value, col } => {
                    // G132..G134 with a weighting value: evaluated, accepted, no motion effect.
                    if let Value::Expr(e) = value {
                        self.eval(e).map_err(|e| e.at(*col))?;
                    }
                    if !apply_g(&mut self.modal, *g, &mut gs) {
                        return Err(DecodeError::new(
                            codes::UNKNOWN_G,
                            format!("unknown G function G{g}"),
                        )
                        .at(*col));
                    }
                }
                Item::Word(w) => {
                    let v = match &w.value {
                        Value::Num(n) => *n,
                        Value::Expr(e) => self.eval(e).map_err(|e| e.at(w.col))?,
                    };
                    match w.letter {
                        b'G' => {
                            let g = whole(v).ok_or_else(|| {
                                DecodeError::new(
                                    codes::UNKNOWN_G,
                                    format!("G{v} is not a G function"),
                                )
                                .at(w.col)
                            })?;
                            if !apply_g(&mut self.modal, g, &mut gs) {
                                return Err(DecodeError::new(
                                    codes::UNKNOWN_G,
                                    format!("unknown G function G{g}"),
                                )
                                .at(w.col));
                            }
                        }
                        b'M' => {
                            let m = whole(v).ok_or_else(|| {
                                DecodeError::new(
                                    codes::UNKNOWN_M,
                                    format!("M{v} is not an M function"),
                                )
                                .at(w.col)
                            })?;
                            if n_ms == ms.len() {
                                return Err(DecodeError::new(
                                    codes::SYNTAX,
                                    "too many M functions in one block",
                                )
                                .at(w.col));
                            }
                            ms[n_ms] = m;
                            n_ms += 1;
                            apply_m(&mut self.modal, m);
                        }
                        b'F' => {
                            if !(v >= 0.0 && v.is_finite()) {
                                return Err(DecodeError::new(
                                    codes::BAD_VALUE,
                                    format!("feed F{v} out of range"),
                                )
                                .at(w.col));
                            }
                            self.modal.feed_mm_per_min = v;
                        }
                        b'S' => self.modal.spindle_rpm = v,
                        b'T' => self.modal.tool = whole(v).unwrap_or(0),
                        b'D' => self.modal.tool_offset = whole(v).unwrap_or(0),
                        b'I' => ijk[0] = Some(v),
                        b'J' => ijk[1] = Some(v),
                        b'K' => ijk[2] = Some(v),
                        b'R' => radius = Some(v),
                        letter => {
                            if let Some(i) = AXIS_LETTERS.iter().position(|&a| a == letter) {
                                if !v.is_finite() {
                                    return Err(DecodeError::new(
                                        codes::BAD_VALUE,
                                        "axis value not finite",
                                    )
                                    .at(w.col));
                                }
                                if !(self.settings.axes[i] || gs.dwell && letter == b'X') {
                                    return Err(DecodeError::new(
                                        codes::SYNTAX,
                                        format!(
                                            "axis {} is not configured in this channel",
                                            letter as char
                                        ),
                                    )
                                    .at(w.col));
                                }
                                axes[i] = Some(v);
                            }
                            // H and E: accepted, no effect in the emulator.
                        }
                    }
                }
            }
        }
        let ms = &ms[..n_ms];
        let info = self.info(block, text, meta, io);
        let mut queued_main = false;
        if gs.dwell {
            let seconds = axes[0].take().unwrap_or(0.0).max(0.0);
            self.emit(info.clone(), Action::Dwell { seconds }, false, io);
            queued_main = true;
        }
        if axes.iter().any(Option::is_some) {
            let start = self.modal.pos;
            let mut end = start;
            let offset = if gs.machine_coords || self.modal.zero_offset == 0 {
                [0.0; MAX_AXES]
            } else {
                self.settings.zero_offsets[self.modal.zero_offset - 1]
            };
            for i in 0..MAX_AXES {
                if let Some(v) = axes[i] {
                    end[i] = if self.modal.absolute {
                        v + offset[i]
                    } else {
                        start[i] + v
                    };
                }
            }
            let feed = self.modal.feed_mm_per_min;
            let mv = match self.modal.motion {
                MotionMode::Rapid => Move {
                    kind: MoveKind::Rapid,
                    start,
                    end,
                    feed_mm_per_min: 0.0,
                },
                m => {
                    if feed <= 0.0 {
                        return Err(DecodeError::new(
                            codes::NO_FEED,
                            "no feed programmed (F) for G1/G2/G3",
                        ));
                    }
                    if m == MotionMode::Linear {
                        Move {
                            kind: MoveKind::Line,
                            start,
                            end,
                            feed_mm_per_min: feed,
                        }
                    } else {
                        arc::arc_move(
                            &arc::ArcSpec {
                                plane: self.modal.plane,
                                ijk,
                                radius,
                                cw: m == MotionMode::ArcCw,
                            },
                            start,
                            end,
                            feed,
                            self.settings.arc_tolerance_mm,
                        )
                        .map_err(|e| {
                            DecodeError::new(
                                codes::ARC_INCONSISTENT,
                                format!("circle not consistent: {e:?}"),
                            )
                        })?
                    }
                }
            };
            self.modal.pos = end;
            self.emit(info.clone(), Action::Move(mv), queued_main, io);
            queued_main = true;
        }
        let end_m = ms.iter().copied().find(|m| matches!(m, 2 | 30 | 17 | 29));
        match end_m {
            Some(m @ (17 | 29)) => {
                if self.top().kind == FrameKind::Main {
                    return Err(DecodeError::new(
                        codes::UNEXPECTED_SUB_END,
                        format!("unexpected M{m} in main program"),
                    ));
                }
                if !queued_main {
                    self.emit(info, Action::None, false, io);
                }
                self.check_open_flow()?;
                self.return_from_subroutine();
            }
            Some(m) => {
                if self.search.is_some() {
                    return Err(DecodeError::new(
                        codes::SEARCH_NOT_FOUND,
                        format!(
                            "block search target {} not found",
                            self.search
                                .map(|s| s.target.to_string())
                                .unwrap_or_default()
                        ),
                    ));
                }
                if self.top().kind != FrameKind::Main {
                    self.notes.push(Note::Warning {
                        code: codes::UNEXPECTED_PROGRAM_END,
                        msg: format!("M{m} in a subroutine: the program ends"),
                    });
                } else {
                    self.check_open_flow()?;
                }
                if !queued_main {
                    self.emit(info.clone(), Action::None, false, io);
                }
                self.emit(info, Action::End { m }, true, io);
                self.end_program();
            }
            None => {
                if !queued_main {
                    self.emit(info, Action::None, false, io);
                }
            }
        }
        Ok(())
    }
}
