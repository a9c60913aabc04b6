//! Pieces of equivalent command lines.

use std::fmt::Display;

/// ` --name value` when `value` differs from `default`.
pub fn push_changed<T: PartialEq + Display>(c: &mut String, name: &str, value: T, default: T) {
    if value != default {
        c.push_str(&format!(" --{name} {value}"));
    }
}

/// ` --name value` when a value was given.
pub fn push_given<T: Display>(c: &mut String, name: &str, value: Option<T>) {
    if let Some(v) = value {
        c.push_str(&format!(" --{name} {v}"));
    }
}

/// ` --name` when the switch is on.
pub fn push_switch(c: &mut String, name: &str, on: bool) {
    if on {
        c.push_str(&format!(" --{name}"));
    }
}
