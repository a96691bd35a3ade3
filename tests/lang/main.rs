//! The NC language: parsing, evaluation, round trips, the ISG dialect and syntax, `ncchannel
//! check`, and the shipped programs run end to end.

#[path = "../support/mod.rs"]
mod support;

mod check_program;
mod dialect;
mod isg_syntax;
mod kernel_language;
mod label_index;
mod lang_eval;
mod lang_parse;
mod lang_roundtrip;
mod real_programs;
