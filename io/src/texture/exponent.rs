//! Stable Micro Systems Exponent text exports ([`read_exponent`]).
//!
//! ```text
//! gel2_I_2_5mm3<TAB>gel2_I_2_5mm3<TAB>gel2_I_2_5mm3<TAB>     line 1: the test's name, once per column
//! Force<TAB>Distance<TAB>Time<TAB>                            line 2: the column names
//! g<TAB>mm<TAB>sec<TAB>                                       line 3: their units
//!                                                             (blank lines are skipped)
//! 0.0231409<TAB>0<TAB>0<TAB>                                  one row per sample
//! ```
//!
//! - Tab-separated, `\n` or `\r\n` line ends, a trailing tab on each line allowed.
//! - Line 2 names the columns `Force`, `Distance` and `Time` (in any order, case
//!   ignored, each once; one test per file); line 3 gives their units, which must
//!   be `g` (grams-force), `mm` and `sec`.
//! - `Force` is converted to N with standard gravity, 1 g = 9.80665e-3 N,
//!   compression positive as the instrument writes it. `Distance` is the probe's
//!   travel downward from where the test started; [`super::RawSample::tool_mm`]
//!   is minus it.
//! - Refused with the line: a missing or wrong name or unit line, a row without
//!   exactly three cells, a cell that is not a finite number, time that does not
//!   increase, a file without rows.

use std::path::Path;

use super::error::ImportError;
use super::raw_test::{
    cells, check_time_order, number, numbered_lines, read_text, shorten, RawFormat, RawSample, RawTest,
};

/// One gram-force in newtons (standard gravity, 9.80665 m/s^2).
pub const GRAM_FORCE_N: f64 = 9.806_65e-3;

/// The Exponent's columns, their required units and what they become.
const COLUMNS: [(&str, &str, &str); 3] =
    [("Force", "g", "grams-force"), ("Distance", "mm", "millimetres"), ("Time", "sec", "seconds")];

/// Reads a Stable Micro Systems Exponent text export (see the module docs).
pub fn read_exponent(path: impl AsRef<Path>) -> Result<RawTest, ImportError> {
    let path = path.as_ref();
    parse_exponent(path, &read_text(path)?)
}

/// Parses the text of an Exponent export; `file` names it in messages.
pub fn parse_exponent(file: &Path, text: &str) -> Result<RawTest, ImportError> {
    let bad = |line: usize, field: &str, cause: String| ImportError::invalid(file, line, field, cause);
    let expected = "an Exponent export: a name line, then `Force  Distance  Time`, then `g  mm  sec`";
    let mut lines = numbered_lines(text);

    // Line 1: the test's name.
    let test_name = match lines.next() {
        Some((_, l)) if !l.trim().is_empty() => cells(l).into_iter().find(|c| !c.is_empty()).map(str::to_string),
        _ => {
            return Err(bad(1, "header", format!("the file is empty or starts with a blank line; expected {expected}")))
        }
    };

    // Line 2: the column names -> the position of Force, Distance, Time.
    let (names_line, names) = match lines.next().map(|(n, l)| (n, cells(l))) {
        Some((n, c)) if !c.is_empty() => (n, c),
        _ => return Err(bad(2, "header", format!("no column names on line 2; expected {expected}"))),
    };
    let mut order = [usize::MAX; 3];
    let names_ok = names.len() == 3
        && COLUMNS.iter().enumerate().all(|(k, (name, _, _))| {
            let found: Vec<usize> = (0..3).filter(|&i| names[i].eq_ignore_ascii_case(name)).collect();
            if let [i] = found[..] {
                order[k] = i;
                true
            } else {
                false
            }
        });
    if !names_ok {
        return Err(bad(
            names_line,
            "header",
            format!(
                "wrong column names \"{}\"; expected Force, Distance and Time (one test per file)",
                shorten(&names.join(", "))
            ),
        ));
    }

    // Line 3: the units.
    let (units_line, units) = match lines.next().map(|(n, l)| (n, cells(l))) {
        Some((n, c)) if !c.is_empty() => (n, c),
        _ => return Err(bad(3, "units", "no units on line 3; expected `g  mm  sec`".into())),
    };
    for (k, (name, unit, what)) in COLUMNS.iter().enumerate() {
        let given = units.get(order[k]).copied().unwrap_or("");
        if given != *unit {
            return Err(bad(units_line, name, format!("unit \"{}\"; expected \"{unit}\" ({what})", shorten(given))));
        }
    }
    if units.len() != 3 {
        return Err(bad(units_line, "units", format!("{} units; expected 3 (g, mm, sec)", units.len())));
    }

    // The rows.
    let mut samples: Vec<RawSample> = Vec::new();
    let mut last_line = units_line;
    for (line, l) in lines {
        last_line = line;
        let c = cells(l);
        if c.is_empty() {
            continue;
        }
        if c.len() != 3 {
            return Err(bad(line, "row", format!("{} cells; expected 3 (Force, Distance, Time)", c.len())));
        }
        let force_g = number(file, line, "Force", c[order[0]])?;
        let distance_mm = number(file, line, "Distance", c[order[1]])?;
        let t_s = number(file, line, "Time", c[order[2]])?;
        if let Some(p) = samples.last() {
            check_time_order(file, line, "Time", t_s, p.t_s)?;
        }
        samples.push(RawSample { line, t_s, force_n: force_g * GRAM_FORCE_N, tool_mm: -distance_mm });
    }
    if samples.is_empty() {
        return Err(bad(last_line, "row", "no data rows after the header".into()));
    }
    Ok(RawTest { file: file.to_path_buf(), format: RawFormat::Exponent, test_name, samples })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "gel\tgel\tgel\t\r\nForce\tDistance\tTime\t\r\ng\tmm\tsec\t\r\n\t\t\t\r\n";

    fn parse(text: &str) -> Result<RawTest, ImportError> {
        parse_exponent(Path::new("t.tab"), text)
    }

    fn refusal(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn reads_rows_in_newtons_and_tool_height() {
        let raw = parse(&format!("{HEAD}1\t0\t0\t\r\n2\t0.5\t0.005\t\r\n")).unwrap();
        assert_eq!(raw.test_name.as_deref(), Some("gel"));
        assert_eq!(raw.format, RawFormat::Exponent);
        assert_eq!(raw.samples.len(), 2);
        let s = raw.samples[1];
        assert_eq!(s.line, 6);
        assert_eq!((s.t_s, s.tool_mm), (0.005, -0.5));
        assert!((s.force_n - 2.0 * 9.80665e-3).abs() < 1e-15);
    }

    #[test]
    fn columns_may_come_in_any_order() {
        let raw = parse("n\nTime\tforce\tDistance\nsec\tg\tmm\n0.5\t10\t0.25\n").unwrap();
        let s = raw.samples[0];
        assert_eq!((s.t_s, s.tool_mm), (0.5, -0.25));
        assert!((s.force_n - 0.0980665).abs() < 1e-15);
    }

    #[test]
    fn refuses_an_empty_file() {
        assert!(refusal("").starts_with("t.tab:1: header: the file is empty"), "{}", refusal(""));
        assert!(refusal("name\n").starts_with("t.tab:2: header: no column names on line 2"), "{}", refusal("name\n"));
        assert!(refusal("name").starts_with("t.tab:2: header: no column names on line 2"));
    }

    #[test]
    fn refuses_a_wrong_header() {
        let e = refusal("n\nForce\tDistance\tStrain\ng\tmm\tsec\n1\t2\t3\n");
        assert!(e.starts_with("t.tab:2: header: wrong column names \"Force, Distance, Strain\""), "{e}");
        // Two tests side by side.
        let e = refusal("n\tn\nForce\tDistance\tTime\tForce\tDistance\tTime\n");
        assert!(e.starts_with("t.tab:2: header: wrong column names"), "{e}");
        // The name line missing: the names are read as the name, the units as names.
        let e = refusal("Force\tDistance\tTime\ng\tmm\tsec\n1\t2\t3\n");
        assert!(e.starts_with("t.tab:2: header:"), "{e}");
    }

    #[test]
    fn refuses_wrong_units_naming_the_column() {
        assert_eq!(
            refusal("n\nForce\tDistance\tTime\nN\tmm\tsec\n1\t2\t3\n"),
            "t.tab:3: Force: unit \"N\"; expected \"g\" (grams-force)"
        );
        assert_eq!(
            refusal("n\nForce\tDistance\tTime\ng\tmm\ts\n1\t2\t3\n"),
            "t.tab:3: Time: unit \"s\"; expected \"sec\" (seconds)"
        );
        assert_eq!(
            refusal("n\nForce\tDistance\tTime\ng\tmm\tsec\tkg\n1\t2\t3\n"),
            "t.tab:3: units: 4 units; expected 3 (g, mm, sec)"
        );
        assert!(refusal("n\nForce\tDistance\tTime\n").starts_with("t.tab:3: units: no units on line 3"));
    }

    #[test]
    fn refuses_a_non_numeric_cell_with_its_line() {
        let e = refusal(&format!("{HEAD}1\t0\t0\t\r\n2\t0,5\t0.005\t\r\n"));
        assert_eq!(e, "t.tab:6: Distance: not a number: \"0,5\"");
        let e = refusal(&format!("{HEAD}1\t0\t0\t\r\nNaN\t0.5\t0.005\t\r\n"));
        assert_eq!(e, "t.tab:6: Force: not a finite number: \"NaN\"");
        let e = refusal(&format!("{HEAD}1\t0\t0\t\r\n1\t0.5\r\n"));
        assert_eq!(e, "t.tab:6: row: 2 cells; expected 3 (Force, Distance, Time)");
    }

    #[test]
    fn refuses_time_going_backwards() {
        let e = refusal(&format!("{HEAD}1\t0\t1\n1\t0\t2\n1\t0\t1.5\n"));
        assert_eq!(e, "t.tab:7: Time: time goes backwards: 1.5 s after 2 s");
        let e = refusal(&format!("{HEAD}1\t0\t1\n1\t0\t1\n"));
        assert!(e.starts_with("t.tab:6: Time: time does not increase"), "{e}");
    }

    #[test]
    fn a_missing_file_is_named_once() {
        let err = read_exponent("no/such/file.tab").unwrap_err().to_string();
        assert!(err.starts_with("no/such/file.tab: cannot read: "), "{err}");
        assert_eq!(err.matches("os error").count(), 1, "{err}");
    }

    #[test]
    fn refuses_a_file_without_rows() {
        assert_eq!(refusal(HEAD), "t.tab:5: row: no data rows after the header");
    }
}
