//! TA Instruments rheometer text exports ([`read_rheometer`]), e.g. a rotational
//! rheometer used in axial compression.
//!
//! ```text
//! Time (s)<TAB>Encoder (rad)<TAB>Torque (Nm)<TAB>Marker<TAB>Normal force (N)<TAB>Gap (um)<TAB>   line 1: NAME (UNIT)
//! 0<TAB>0<TAB>-0.000001115460423<TAB>0<TAB>0.02288926024<TAB>8994.76953125<TAB>              one row per sample
//! ```
//!
//! - Tab-separated, `\n` or `\r\n` line ends, a trailing tab on each line allowed,
//!   blank lines skipped.
//! - Line 1 names the columns, each `NAME (UNIT)` or `NAME`. Three are read,
//!   found by name (case ignored) wherever they stand, and their units must be:
//!   `Time (s)`, `Normal force (N)` (compression positive) and `Gap (um)` (the
//!   distance between the plates in micrometres, `µm` also accepted). Other
//!   columns (`Encoder`, `Torque`, `Marker`, ...) are not read.
//! - [`super::RawSample::tool_mm`] is the gap in mm: the upper plate's height
//!   above the lower one, so the specimen's height at first touch can be read
//!   from it.
//! - Refused with the line: a header without these columns or with other units,
//!   a row whose number of cells differs from the header's, a cell of the three
//!   columns that is not a finite number, time that does not increase, a file
//!   without rows.

use std::path::Path;

use super::error::ImportError;
use super::raw_test::{
    cells, check_time_order, number, numbered_lines, read_text, shorten, RawFormat, RawSample, RawTest,
};

/// The columns read: name, accepted units, the unit's meaning.
const COLUMNS: [(&str, &[&str], &str); 3] =
    [("Time", &["s"], "seconds"), ("Normal force", &["N"], "newtons"), ("Gap", &["um", "µm", "μm"], "micrometres")];

/// The header this reader expects, for messages.
const EXPECTED: &str = "TA Instruments columns, tab-separated, among them Time (s), Normal force (N) and Gap (um)";

/// Reads a TA Instruments rheometer text export (see the module docs).
pub fn read_rheometer(path: impl AsRef<Path>) -> Result<RawTest, ImportError> {
    let path = path.as_ref();
    parse_rheometer(path, &read_text(path)?)
}

/// `NAME (UNIT)` -> (`NAME`, `Some(UNIT)`); `NAME` -> (`NAME`, `None`).
fn name_and_unit(cell: &str) -> (&str, Option<&str>) {
    if let Some(open) = cell.rfind(" (") {
        if let Some(unit) = cell[open + 2..].strip_suffix(')') {
            return (cell[..open].trim(), Some(unit.trim()));
        }
    }
    (cell, None)
}

/// Parses the text of a rheometer export; `file` names it in messages.
pub fn parse_rheometer(file: &Path, text: &str) -> Result<RawTest, ImportError> {
    let bad = |line: usize, field: &str, cause: String| ImportError::invalid(file, line, field, cause);
    let mut lines = numbered_lines(text);
    let header = match lines.next() {
        Some((_, l)) if !l.trim().is_empty() => cells(l),
        _ => {
            return Err(bad(1, "header", format!("the file is empty or starts with a blank line; expected {EXPECTED}")))
        }
    };
    // The position of Time, Normal force and Gap in the header, then their units.
    let mut at = [0usize; 3];
    for (k, (name, _, _)) in COLUMNS.iter().enumerate() {
        let found: Vec<usize> =
            (0..header.len()).filter(|&i| name_and_unit(header[i]).0.eq_ignore_ascii_case(name)).collect();
        at[k] = match found[..] {
            [i] => i,
            [] => {
                return Err(bad(
                    1,
                    "header",
                    format!("wrong header \"{}\": no column {name}; expected {EXPECTED}", shorten(&header.join(", "))),
                ))
            }
            _ => return Err(bad(1, "header", format!("the column {name} appears {} times", found.len()))),
        };
    }
    for (k, (_, units, meaning)) in COLUMNS.iter().enumerate() {
        let unit = name_and_unit(header[at[k]]).1.unwrap_or("");
        if !units.contains(&unit) {
            return Err(bad(
                1,
                header[at[k]],
                format!("unit \"{}\"; expected \"{}\" ({meaning})", shorten(unit), units[0]),
            ));
        }
    }
    let columns = [header[at[0]], header[at[1]], header[at[2]]];

    let mut samples: Vec<RawSample> = Vec::new();
    let mut last_line = 1;
    for (line, l) in lines {
        last_line = line;
        let c = cells(l);
        if c.is_empty() {
            continue;
        }
        if c.len() != header.len() {
            return Err(bad(line, "row", format!("{} cells; the header has {}", c.len(), header.len())));
        }
        let t_s = number(file, line, columns[0], c[at[0]])?;
        let force_n = number(file, line, columns[1], c[at[1]])?;
        let gap_um = number(file, line, columns[2], c[at[2]])?;
        if let Some(p) = samples.last() {
            check_time_order(file, line, columns[0], t_s, p.t_s)?;
        }
        samples.push(RawSample { line, t_s, force_n, tool_mm: gap_um * 1e-3 });
    }
    if samples.is_empty() {
        return Err(bad(last_line, "row", "no data rows after the header".into()));
    }
    Ok(RawTest { file: file.to_path_buf(), format: RawFormat::Rheometer, test_name: None, samples })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "Time (s)\tEncoder (rad)\tTorque (Nm)\tMarker\tNormal force (N)\tGap (um)\t\n";

    fn parse(text: &str) -> Result<RawTest, ImportError> {
        parse_rheometer(Path::new("r.txt"), text)
    }

    fn refusal(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn reads_time_force_and_gap_in_mm() {
        let raw = parse(&format!(
            "{HEAD}0\t0\t-1E-06\t0\t0.0229\t8994.76953125\t\n0.00208\t4.5E-08\t-1.1E-06\t0\t0.0213\t8994.5\t\n"
        ))
        .unwrap();
        assert_eq!(raw.format, RawFormat::Rheometer);
        assert_eq!(raw.samples.len(), 2);
        let s = raw.samples[1];
        assert_eq!((s.line, s.t_s, s.force_n), (3, 0.00208, 0.0213));
        assert!((s.tool_mm - 8.9945).abs() < 1e-12);
    }

    #[test]
    fn columns_are_found_by_name() {
        let raw = parse("Gap (µm)\tNormal Force (N)\tTime (s)\r\n9000\t0.5\t1.5\r\n").unwrap();
        let s = raw.samples[0];
        assert_eq!((s.t_s, s.force_n, s.tool_mm), (1.5, 0.5, 9.0));
    }

    /// A TA rheometer export saved as Latin-1: `µm` is the single byte 0xB5.
    #[test]
    fn a_latin1_header_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.txt");
        let mut bytes = b"Gap (".to_vec();
        bytes.push(0xB5);
        bytes.extend_from_slice(b"m)\tNormal Force (N)\tTime (s)\r\n9000\t0.5\t1.5\r\n");
        std::fs::write(&path, &bytes).unwrap();
        let raw = read_rheometer(&path).unwrap();
        assert_eq!(raw.samples.len(), 1);
        assert_eq!(raw.samples[0].tool_mm, 9.0);
        // A file with control bytes is still refused, with its line.
        std::fs::write(&path, b"Gap (um)\tNormal Force (N)\tTime (s)\n\x01\xB5\n").unwrap();
        let e = read_rheometer(&path).unwrap_err().to_string();
        assert!(e.contains("r.txt:2: row: not valid UTF-8"), "{e}");
    }

    #[test]
    fn refuses_a_wrong_header() {
        assert!(refusal("").starts_with("r.txt:1: header: the file is empty"));
        let e = refusal("Time (s)\tForce (N)\tGap (um)\n1\t2\t3\n");
        assert!(
            e.starts_with("r.txt:1: header: wrong header \"Time (s), Force (N), Gap (um)\": no column Normal force"),
            "{e}"
        );
        let e = refusal("Force\tDistance\tTime\ng\tmm\tsec\n");
        assert!(e.starts_with("r.txt:1: header: wrong header"), "{e}");
        let e = refusal("Time (s)\tNormal force (N)\tGap (um)\tGap (um)\n");
        assert_eq!(e, "r.txt:1: header: the column Gap appears 2 times");
    }

    #[test]
    fn refuses_wrong_units() {
        assert_eq!(
            refusal("Time (min)\tNormal force (N)\tGap (um)\n1\t2\t3\n"),
            "r.txt:1: Time (min): unit \"min\"; expected \"s\" (seconds)"
        );
        assert_eq!(
            refusal("Time (s)\tNormal force (N)\tGap (mm)\n1\t2\t3\n"),
            "r.txt:1: Gap (mm): unit \"mm\"; expected \"um\" (micrometres)"
        );
        assert_eq!(
            refusal("Time (s)\tNormal force\tGap (um)\n1\t2\t3\n"),
            "r.txt:1: Normal force: unit \"\"; expected \"N\" (newtons)"
        );
    }

    #[test]
    fn refuses_non_numeric_and_non_finite_cells_with_their_line() {
        let e = refusal(&format!("{HEAD}0\t0\t0\t0\t0.1\t9000\t\n0.1\t0\t0\t0\tabc\t9000\t\n"));
        assert_eq!(e, "r.txt:3: Normal force (N): not a number: \"abc\"");
        let e = refusal(&format!("{HEAD}0\t0\t0\t0\t0.1\tNaN\t\n"));
        assert_eq!(e, "r.txt:2: Gap (um): not a finite number: \"NaN\"");
        let e = refusal(&format!("{HEAD}0\t0\t0\t0\t0.1\t\n"));
        assert_eq!(e, "r.txt:2: row: 5 cells; the header has 6");
    }

    #[test]
    fn refuses_time_going_backwards() {
        let e = refusal(&format!("{HEAD}1\t0\t0\t0\t0.1\t9000\n0.5\t0\t0\t0\t0.1\t9000\n"));
        assert_eq!(e, "r.txt:3: Time (s): time goes backwards: 0.5 s after 1 s");
    }

    #[test]
    fn refuses_a_file_without_rows() {
        assert_eq!(refusal(HEAD), "r.txt:2: row: no data rows after the header");
    }
}
