//! [`RawTest`]: the samples of one raw file in SI-like units (s, N, mm), and the
//! text handling the two readers share.

use std::path::{Path, PathBuf};

use super::error::ImportError;

/// The instrument export a [`RawTest`] was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawFormat {
    /// Stable Micro Systems Exponent text export ([`super::read_exponent`]).
    Exponent,
    /// TA Instruments rheometer text export ([`super::read_rheometer`]).
    Rheometer,
}

impl RawFormat {
    /// A short name, as written in a bundle's `[extra] source_format`.
    pub fn as_str(self) -> &'static str {
        match self {
            RawFormat::Exponent => "exponent",
            RawFormat::Rheometer => "rheometer",
        }
    }

    /// The force column as the file's header names it (for messages).
    pub fn force_column(self) -> &'static str {
        match self {
            RawFormat::Exponent => "Force",
            RawFormat::Rheometer => "Normal force (N)",
        }
    }

    /// The tool position column as the file's header names it (for messages).
    pub fn tool_column(self) -> &'static str {
        match self {
            RawFormat::Exponent => "Distance",
            RawFormat::Rheometer => "Gap (um)",
        }
    }

    /// The time column as the file's header names it (for messages).
    pub fn time_column(self) -> &'static str {
        match self {
            RawFormat::Exponent => "Time",
            RawFormat::Rheometer => "Time (s)",
        }
    }

    /// Whether [`RawSample::tool_mm`] is the tool's height above the lower plate
    /// (the rheometer's gap) rather than relative to where the test started.
    pub fn tool_is_absolute(self) -> bool {
        self == RawFormat::Rheometer
    }
}

/// One row of a raw file, converted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawSample {
    /// The row's 1-based line in the file.
    pub line: usize,
    /// Time [s], as the instrument counts it.
    pub t_s: f64,
    /// Force on the specimen [N], compression positive, not zeroed.
    pub force_n: f64,
    /// Tool height [mm], up positive: the gap for the rheometer (the height above
    /// the lower plate), minus the distance travelled for the Exponent (0 where
    /// the test started). The tool's downward displacement from first touch is
    /// `tool_mm(touch) - tool_mm(t)`.
    pub tool_mm: f64,
}

/// A raw test: the rows of one instrument file, in file order, converted to
/// s, N and mm. Built by [`super::read_exponent`] and [`super::read_rheometer`]
/// (or by hand, e.g. for synthetic tests: [`super::to_bundle`] checks it again).
#[derive(Debug, Clone, PartialEq)]
pub struct RawTest {
    /// The file, as the caller gave it (used in messages).
    pub file: PathBuf,
    /// The instrument export.
    pub format: RawFormat,
    /// The test's name in the file, when it has one (the Exponent's first line).
    pub test_name: Option<String>,
    /// The rows, in strictly increasing time.
    pub samples: Vec<RawSample>,
}

impl RawTest {
    /// Refuses samples that are not finite or not in strictly increasing time,
    /// naming the line; the readers refuse them already, this guards hand-built tests.
    pub(crate) fn check(&self) -> Result<(), ImportError> {
        let f = self.format;
        let mut previous: Option<&RawSample> = None;
        for s in &self.samples {
            for (column, value) in
                [(f.time_column(), s.t_s), (f.force_column(), s.force_n), (f.tool_column(), s.tool_mm)]
            {
                if !value.is_finite() {
                    return Err(ImportError::invalid(&self.file, s.line, column, format!("{value} is not finite")));
                }
            }
            if let Some(p) = previous {
                check_time_order(&self.file, s.line, f.time_column(), s.t_s, p.t_s)?;
            }
            previous = Some(s);
        }
        Ok(())
    }
}

/// Refuses a time that does not increase.
pub(crate) fn check_time_order(
    file: &Path,
    line: usize,
    column: &str,
    t: f64,
    previous: f64,
) -> Result<(), ImportError> {
    if t < previous {
        return Err(ImportError::invalid(file, line, column, format!("time goes backwards: {t} s after {previous} s")));
    }
    if t == previous {
        return Err(ImportError::invalid(file, line, column, format!("time does not increase: a second row at {t} s")));
    }
    Ok(())
}

/// Reads `file` as text: UTF-8, a leading byte-order mark dropped; a file that
/// is not UTF-8 but plain Latin-1 text (as instruments on Windows write it, e.g.
/// `µm` as the byte 0xB5) is read as Latin-1. Anything else (control bytes) is
/// refused with the line of the first byte that is not UTF-8.
pub(crate) fn read_text(file: &Path) -> Result<String, ImportError> {
    let bytes = crate::input::read(file).map_err(|reason| ImportError::Read { file: file.to_path_buf(), reason })?;
    decode(file, bytes)
}

/// Whether `bytes` read as Latin-1 are printable text: no control byte other
/// than tab, line feed and carriage return (and none of 0x7F-0x9F, which
/// Latin-1 leaves to controls).
fn is_latin1_text(bytes: &[u8]) -> bool {
    bytes.iter().all(|&b| matches!(b, b'\t' | b'\n' | b'\r' | 0x20..=0x7E | 0xA0..=0xFF))
}

pub(crate) fn decode(file: &Path, bytes: Vec<u8>) -> Result<String, ImportError> {
    match String::from_utf8(bytes) {
        Ok(mut text) => {
            if text.starts_with('\u{feff}') {
                text.drain(..'\u{feff}'.len_utf8());
            }
            Ok(text)
        }
        Err(e) if is_latin1_text(e.as_bytes()) => Ok(e.into_bytes().iter().map(|&b| char::from(b)).collect()),
        Err(e) => {
            let valid = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..valid].iter().filter(|&&b| b == b'\n').count();
            Err(ImportError::invalid(file, line, "row", "not valid UTF-8 text"))
        }
    }
}

/// The lines of `text` with their 1-based numbers, line ends (`\n`, `\r\n`)
/// removed.
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n').enumerate().map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// The tab-separated cells of a line, trimmed, with trailing empty cells (the
/// exports end rows with a tab) removed.
pub(crate) fn cells(line: &str) -> Vec<&str> {
    let mut c: Vec<&str> = line.split('\t').map(str::trim).collect();
    while c.last().is_some_and(|s| s.is_empty()) {
        c.pop();
    }
    c
}

/// A finite number from a cell, or the refusal naming the line and column.
pub(crate) fn number(file: &Path, line: usize, column: &str, cell: &str) -> Result<f64, ImportError> {
    let x: f64 = cell
        .parse()
        .map_err(|_| ImportError::invalid(file, line, column, format!("not a number: \"{}\"", shorten(cell))))?;
    if !x.is_finite() {
        return Err(ImportError::invalid(file, line, column, format!("not a finite number: \"{}\"", shorten(cell))));
    }
    Ok(x)
}

/// `text` cut to at most 40 characters for a message.
pub(crate) fn shorten(text: &str) -> String {
    const MAX: usize = 40;
    if text.chars().count() <= MAX {
        text.to_string()
    } else {
        format!("{}...", text.chars().take(MAX).collect::<String>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_drop_the_trailing_tab_and_trim() {
        assert_eq!(cells("1\t2 \t 3\t\r".trim_end_matches('\r')), vec!["1", "2", "3"]);
        assert_eq!(cells(""), Vec::<&str>::new());
        assert_eq!(cells("\t\t"), Vec::<&str>::new());
        assert_eq!(cells("a\t\tb"), vec!["a", "", "b"]);
    }

    #[test]
    fn lines_are_numbered_from_one_and_lose_their_ends() {
        let l: Vec<_> = numbered_lines("a\r\nb\nc").collect();
        assert_eq!(l, vec![(1, "a"), (2, "b"), (3, "c")]);
    }

    #[test]
    fn invalid_utf8_names_its_line() {
        // Not UTF-8 and not Latin-1 text either (a control byte).
        let err = decode(Path::new("x.txt"), b"ok\nok\n\x01\xff\n".to_vec()).unwrap_err();
        assert_eq!(err.to_string(), "x.txt:3: row: not valid UTF-8 text");
        // Latin-1 text: read as such.
        assert_eq!(decode(Path::new("x.txt"), b"Gap (\xb5m)\n".to_vec()).unwrap(), "Gap (\u{b5}m)\n");
        assert_eq!(decode(Path::new("x"), "\u{feff}a".as_bytes().to_vec()).unwrap(), "a");
    }

    #[test]
    fn numbers_must_be_finite() {
        let p = Path::new("f");
        assert_eq!(number(p, 4, "Force", "1.5e-3").unwrap(), 1.5e-3);
        for bad in ["NaN", "inf", "-infinity", "1,5", "", "x"] {
            assert!(number(p, 4, "Force", bad).is_err(), "{bad}");
        }
        assert_eq!(number(p, 7, "Force", "abc").unwrap_err().to_string(), "f:7: Force: not a number: \"abc\"");
    }
}
