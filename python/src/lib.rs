//! `wagashi._wagashi`: the native half of the Python package `wagashi`.
//!
//! It runs a `wagashi` command line through the same library function as the
//! binary (`wagashi_cli::run_command`), so that a Python call and the command
//! line give the same outputs bit for bit. The Python half (`wagashi/`) turns
//! keyword options into that command line and reads the outputs back.
//!
//! - [`run`]: one command, the GIL released, optionally in a rayon pool of its
//!   own size; returns what the command prints for the user.
//! - [`set_toml_keys`]: a bundle's `experiment.toml` with dotted keys set or
//!   removed (the parameter grids of `wagashi.distributed.press_sweep`).
//!
//! Errors raise `wagashi.WagashiError`, whose message is the binary's one line
//! (`file:line: key: cause`); `wagashi.OptionError`, its subclass, for options
//! that do not parse (the binary's exit status 2).

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use wagashi_cli::{run_command, CommandError};

create_exception!(
    _wagashi,
    WagashiError,
    PyException,
    "A wagashi command failed; the message is the command line's one-line error (file:line: key: cause)."
);
create_exception!(
    _wagashi,
    OptionError,
    WagashiError,
    "The options do not form a valid command line (an unknown option, a bad value)."
);

/// Runs the command line `argv` (without the program name) with the GIL
/// released; `threads`: the size of the rayon pool the run uses (`None`:
/// rayon's global pool, one thread per core). Returns what the command prints
/// for the user (stdout for the binary).
#[pyfunction]
#[pyo3(signature = (argv, threads=None))]
fn run(py: Python<'_>, argv: Vec<String>, threads: Option<usize>) -> PyResult<String> {
    if threads == Some(0) {
        return Err(OptionError::new_err("threads: must be at least 1"));
    }
    let outcome = py.detach(move || -> Result<Vec<u8>, CommandError> {
        let full = std::iter::once("wagashi".to_string()).chain(argv);
        let mut out = Vec::new();
        match threads {
            Some(n) => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| CommandError::Failed(format!("threads = {n}: cannot start the thread pool: {e}")))?;
                pool.install(|| run_command(full, &mut out))?;
            }
            None => run_command(full, &mut out)?,
        }
        Ok(out)
    });
    match outcome {
        Ok(out) => Ok(String::from_utf8_lossy(&out).into_owned()),
        Err(CommandError::Usage(message)) => Err(OptionError::new_err(message)),
        Err(CommandError::Failed(message)) => Err(WagashiError::new_err(message)),
    }
}

/// `text` (a TOML document, read from `file` for the messages) with each
/// `(dotted_key, json_value)` of `keys` set, tables created as needed; a JSON
/// `null` removes the key. Comments and layout are not kept.
#[pyfunction]
fn set_toml_keys(file: &str, text: &str, keys: Vec<(String, String)>) -> PyResult<String> {
    let mut doc: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| WagashiError::new_err(format!("{file}: {}", one_line(&e.to_string()))))?;
    for (key, json) in keys {
        let value: serde_json::Value = serde_json::from_str(&json)
            .map_err(|e| OptionError::new_err(format!("{file}: {key}: not a value: {e}")))?;
        set_key(&mut doc, &key, value).map_err(|why| OptionError::new_err(format!("{file}: {key}: {why}")))?;
    }
    toml::to_string(&doc).map_err(|e| WagashiError::new_err(format!("{file}: {e}")))
}

/// Sets (or with `null` removes) the dotted `key` of `doc`.
fn set_key(doc: &mut toml::Table, key: &str, value: serde_json::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("an empty part in the dotted key".into());
    }
    let (last, path) = parts.split_last().expect("split gives at least one part");
    let mut table = doc;
    for (i, part) in path.iter().enumerate() {
        let entry = table.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        table = entry.as_table_mut().ok_or_else(|| format!("{} is not a table", parts[..=i].join(".")))?;
    }
    if value.is_null() {
        table.remove(*last);
        return Ok(());
    }
    let value = toml::Value::try_from(value).map_err(|e| format!("not a TOML value: {e}"))?;
    table.insert(last.to_string(), value);
    Ok(())
}

fn one_line(text: &str) -> String {
    text.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ")
}

#[pymodule]
fn _wagashi(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(set_toml_keys, m)?)?;
    m.add("WagashiError", m.py().get_type::<WagashiError>())?;
    m.add("OptionError", m.py().get_type::<OptionError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
