//! CSV cells as the tables of the studies write them.

/// A CSV field: quoted when it holds a comma, a quote or a line break.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// A number for CSV: 7 significant digits, empty when not finite.
pub fn csv_num(x: f64) -> String {
    if x.is_finite() { format!("{x:.6e}") } else { String::new() }
}
