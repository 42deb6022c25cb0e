//! Where each key of a TOML file stands: key paths to lines, and toml's errors
//! turned into `FILE:LINE: FIELD: CAUSE` messages.
//!
//! The text is parsed once more into toml's spanned document (`toml::de::DeTable`,
//! whose keys and values are `toml::Spanned`) and every key path is recorded with
//! the byte ranges of its key and value. Key paths join table keys with `.` and
//! array items with `[i]`: `specimen.layers[1].thickness_mm`, `protocol.waypoints[2]`.

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::error::BundleError;

#[derive(Debug, Clone, PartialEq, Eq)]
struct Entry {
    path: String,
    key: Range<usize>,
    value: Range<usize>,
}

/// Key paths of one TOML file and the lines they stand on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SourceMap {
    file: PathBuf,
    line_starts: Vec<usize>,
    entries: Vec<Entry>,
}

impl SourceMap {
    /// Maps `text`, the content of `file`. A syntax error is returned as an
    /// [`BundleError::Invalid`] that names its line.
    pub(crate) fn parse(file: &Path, text: &str) -> Result<Self, BundleError> {
        let line_starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        let (doc, errors) = DeTable::parse_recoverable(text);
        let mut map = SourceMap { file: file.to_path_buf(), line_starts, entries: Vec::new() };
        walk_table(doc.get_ref(), "", &mut map.entries);
        if let Some(err) = errors.into_iter().next() {
            return Err(map.syntax_error(&err, text));
        }
        Ok(map)
    }

    /// The file this map describes.
    pub(crate) fn file(&self) -> &Path {
        &self.file
    }

    /// 1-based line of byte `offset`.
    fn line_of_offset(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    /// The line of `path`'s key, or of its nearest enclosing table that is written
    /// in the file, or 1.
    pub(crate) fn line(&self, path: &str) -> usize {
        let mut p = path;
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == p) {
                return self.line_of_offset(e.key.start);
            }
            match p.rfind(['.', '[']) {
                Some(i) => p = &p[..i],
                None => return 1,
            }
        }
    }

    /// An [`BundleError::Invalid`] for `field`, on the line of `field` (or of its table).
    pub(crate) fn invalid(&self, field: &str, cause: impl Into<String>) -> BundleError {
        BundleError::Invalid {
            file: self.file.clone(),
            line: self.line(field),
            field: field.to_string(),
            cause: cause.into(),
        }
    }

    /// The innermost entry whose key or value range holds `span`.
    fn entry_at(&self, span: &Range<usize>) -> Option<&Entry> {
        let holds = |r: &Range<usize>| r.start <= span.start && span.end <= r.end && !(r.is_empty() && span.is_empty());
        // Parents are recorded before their children: on a tie, the deeper entry wins.
        self.entries.iter().rev().filter(|e| holds(&e.key) || holds(&e.value)).min_by_key(|e| {
            let k = if holds(&e.key) { e.key.len() } else { usize::MAX };
            let v = if holds(&e.value) { e.value.len() } else { usize::MAX };
            k.min(v)
        })
    }

    /// Turns a deserialization error of this file into `FILE:LINE: FIELD: CAUSE`.
    pub(crate) fn toml_error(&self, err: &toml::de::Error) -> BundleError {
        let message = err.message().trim().to_string();
        let span = err.span().unwrap_or(0..0);
        let entry = self.entry_at(&span);
        let base = entry.map(|e| e.path.clone()).unwrap_or_default();
        let quoted = |prefix: &str| -> Option<(String, String)> {
            let rest = message.strip_prefix(prefix)?;
            let end = rest.find('`')?;
            Some((rest[..end].to_string(), rest[end + 1..].to_string()))
        };
        let (field, cause) = if let Some((name, rest)) = quoted("missing field `") {
            // The span is that of the table the key is missing from.
            let table = entry.filter(|e| e.value == span).map(|e| e.path.clone()).unwrap_or_default();
            (join(&table, &name), format!("missing required key{rest}"))
        } else if let Some((name, rest)) = quoted("unknown field `") {
            let field = if base.is_empty() { name } else { base };
            (field, format!("unknown key (a typo?){rest}"))
        } else if let Some(rest) = message.strip_prefix("invalid type: ") {
            (base, format!("wrong type: found {rest}"))
        } else {
            (base, message.clone())
        };
        BundleError::Invalid {
            file: self.file.clone(),
            line: self.line_of_offset(span.start),
            field: if field.is_empty() { "(document)".into() } else { field },
            cause,
        }
    }

    fn syntax_error(&self, err: &toml::de::Error, text: &str) -> BundleError {
        let span = err.span().unwrap_or(0..0);
        let field = self
            .entry_at(&span)
            .map(|e| e.path.clone())
            .or_else(|| key_on_line(text, self.line_of_offset(span.start)))
            .unwrap_or_else(|| "(toml syntax)".into());
        BundleError::Invalid {
            file: self.file.clone(),
            line: self.line_of_offset(span.start),
            field,
            cause: format!("not valid TOML: {}", err.message().trim()),
        }
    }
}

/// The dotted key a broken line `line` seems to set, prefixed by the nearest
/// table header above it: a best guess for naming the field of a syntax error.
fn key_on_line(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let here = lines.get(line.checked_sub(1)?)?.trim();
    let is_key = |k: &str| !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c));
    let header = |l: &str| -> Option<String> {
        let inner = l.trim().strip_prefix('[')?.trim_start_matches('[');
        let name = inner.split(']').next()?.trim();
        is_key(name).then(|| name.to_string())
    };
    if let Some(h) = header(here) {
        return Some(h);
    }
    let key = here.split('=').next()?.trim();
    if !is_key(key) {
        return None;
    }
    let table = lines[..line - 1].iter().rev().find_map(|l| header(l)).unwrap_or_default();
    Some(join(&table, key))
}

fn join(table: &str, key: &str) -> String {
    if table.is_empty() {
        key.to_string()
    } else {
        format!("{table}.{key}")
    }
}

fn walk_table(table: &DeTable<'_>, prefix: &str, out: &mut Vec<Entry>) {
    for (key, value) in table.iter() {
        let path = join(prefix, key.get_ref());
        out.push(Entry { path: path.clone(), key: key.span(), value: value.span() });
        walk_value(value, &path, out);
    }
}

fn walk_value(value: &Spanned<DeValue<'_>>, path: &str, out: &mut Vec<Entry>) {
    match value.get_ref() {
        DeValue::Table(t) => walk_table(t, path, out),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let item_path = format!("{path}[{i}]");
                out.push(Entry { path: item_path.clone(), key: item.span(), value: item.span() });
                walk_value(item, &item_path, out);
            }
        }
        _ => {}
    }
}
