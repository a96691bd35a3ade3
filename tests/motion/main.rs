//! Motion: release rules and profiles, the channel's contouring, jerk limits and corner filters,
//! the pace on the shipped axes.

#[path = "../support/mod.rs"]
mod support;

mod motion;
mod motion_channel;
mod motion_jerk;
mod motion_pace;
mod techno;
