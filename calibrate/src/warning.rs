//! Identifiability warnings, each with a plain-words [`Display`](std::fmt::Display).
//!
//! They come from [`crate::uncertainty`](mod@crate::uncertainty) (the Jacobian at the fit) and
//! [`crate::profile`](mod@crate::profile) (refits along one parameter). None stops a calibration;
//! each says which parameters the data do not pin down, and why.

use std::fmt;

/// Which end of a parameter's range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The lower bound or end.
    Lower,
    /// The upper bound or end.
    Upper,
    /// Both ends.
    Both,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::Lower => "lower",
            Side::Upper => "upper",
            Side::Both => "lower and upper",
        })
    }
}

/// One parameter's share of a direction in parameter space.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    /// The parameter's name.
    pub parameter: String,
    /// Its change along the direction: in `ln x` when `log`, else in its unit.
    /// The largest is 1 in magnitude and the first is positive.
    pub coefficient: f64,
    /// Whether the change is of `ln x` (log-scale parameter).
    pub log: bool,
}

impl fmt::Display for Term {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.log {
            write!(f, "ln({}) by {:+.3}", self.parameter, self.coefficient)
        } else {
            write!(f, "{} by {:+.3e}", self.parameter, self.coefficient)
        }
    }
}

/// Something the data do not determine well.
#[derive(Clone, Debug, PartialEq)]
pub enum Warning {
    /// The scaled Jacobian has numerical rank below `num_parameters`: moving
    /// along `combination` does not change the residuals (to first order).
    RankDeficient { rank: usize, num_parameters: usize, combination: Vec<Term> },
    /// The scaled Jacobian's condition number exceeds 1e8; `parameters` are the
    /// ones in its weakest direction.
    IllConditioned { condition_number: f64, parameters: Vec<String> },
    /// Two parameters' estimates are correlated beyond 0.99 in magnitude.
    HighCorrelation { first: String, second: String, correlation: f64 },
    /// The profile never crosses the 95 % threshold before the bound(s) on `side`.
    FlatProfile { parameter: String, side: Side },
    /// The parameter ended at a bound: the fit would move it outside the box.
    AtBound { parameter: String, value: f64, side: Side },
    /// The 95 % interval is wider than the value itself (relative width > 100 %).
    WideInterval { parameter: String, lower: f64, upper: f64, relative_width: f64 },
    /// A profile refit found a lower objective than the fit: the fit stopped
    /// early or in a local minimum.
    BetterFitInProfile { parameter: String, value: f64, objective: f64, best: f64 },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::RankDeficient { rank, num_parameters, combination } => {
                let names: Vec<&str> = combination.iter().map(|t| t.parameter.as_str()).collect();
                let moves: Vec<String> = combination.iter().map(Term::to_string).collect();
                write!(
                    f,
                    "rank deficiency ({rank} of {num_parameters} directions determined): the data cannot tell apart {}; \
                     changing {} (or any multiple of this) leaves the residuals unchanged",
                    join_names(&names),
                    moves.join(" and ")
                )
            }
            Warning::IllConditioned { condition_number, parameters } => {
                let names: Vec<&str> = parameters.iter().map(String::as_str).collect();
                write!(
                    f,
                    "ill-conditioned: the scaled Jacobian has condition number {condition_number:.2e} (above 1e8); \
                     {} are nearly interchangeable, and their estimates swing widely with the noise",
                    join_names(&names)
                )
            }
            Warning::HighCorrelation { first, second, correlation } => write!(
                f,
                "{first} and {second} are correlated (r = {correlation:+.4}): the data mostly determine a \
                 combination of the two, not each one"
            ),
            Warning::FlatProfile { parameter, side } => {
                let ends = if *side == Side::Both { "ends" } else { "end" };
                write!(
                    f,
                    "flat profile: refitting the others, {parameter} can move to the {side} {ends} of its range \
                     without the fit getting significantly worse (95 %); the data do not bound it there"
                )
            }
            Warning::AtBound { parameter, value, side } => write!(
                f,
                "{parameter} = {} is at its {side} bound: the best fit lies outside the box, and its \
                 interval only describes the fit with the bound in force",
                number(*value)
            ),
            // The relative width (above 100 % here, often by orders of
            // magnitude, or infinite) is not printed: past the value itself it
            // says nothing more than "not determined". For a positive interval
            // the ratio of its ends is what a log-scale parameter's width means.
            Warning::WideInterval { parameter, lower, upper, relative_width: _ } => {
                write!(
                    f,
                    "{parameter} is poorly determined: its 95 % interval [{}, {}] is wider than its value",
                    number(*lower),
                    number(*upper)
                )?;
                let ratio = upper / lower;
                if *lower > 0.0 && ratio.is_finite() {
                    write!(f, " (its ends a factor {} apart)", number(ratio))?;
                }
                Ok(())
            }
            Warning::BetterFitInProfile { parameter, value, objective, best } => write!(
                f,
                "with {parameter} held at {} a refit reached objective {}, below the fit's {}: the fit stopped \
                 early or in a local minimum; fit again from there (or use multi-start)",
                number(*value),
                number(*objective),
                number(*best)
            ),
        }
    }
}

/// Four significant digits, plain for magnitudes in [1e-3, 1e5), else in
/// exponent form (a misfit of a fit to noise-free data is far below 1e-3).
pub fn number(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude == 0.0 || !magnitude.is_finite() {
        format!("{value}")
    } else if (1e-3..1e5).contains(&magnitude) {
        let decimals = (3 - magnitude.log10().floor() as i32).max(0) as usize;
        format!("{value:.decimals$}")
    } else {
        format!("{value:.3e}")
    }
}

/// "a", "a and b", "a, b and c".
fn join_names(names: &[&str]) -> String {
    match names {
        [] => String::from("(none)"),
        [only] => (*only).to_string(),
        [head @ .., last] => format!("{} and {last}", head.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_read_as_sentences() {
        let warning = Warning::RankDeficient {
            rank: 1,
            num_parameters: 2,
            combination: vec![
                Term { parameter: "E1_MPa".into(), coefficient: 1.0, log: true },
                Term { parameter: "nu".into(), coefficient: -0.25, log: false },
            ],
        };
        assert_eq!(
            warning.to_string(),
            "rank deficiency (1 of 2 directions determined): the data cannot tell apart E1_MPa and nu; changing \
             ln(E1_MPa) by +1.000 and nu by -2.500e-1 (or any multiple of this) leaves the residuals unchanged"
        );
        let flat = Warning::FlatProfile { parameter: "c3_MPa_s".into(), side: Side::Both };
        assert!(flat.to_string().contains("lower and upper ends"));
        assert_eq!(join_names(&["a", "b", "c"]), "a, b and c");
        let wide = Warning::WideInterval {
            parameter: "c1_MPa_s".into(),
            lower: 0.0123456,
            upper: 123456.0,
            relative_width: 2.5,
        };
        assert_eq!(
            wide.to_string(),
            "c1_MPa_s is poorly determined: its 95 % interval [0.01235, 1.235e5] is wider than its value (its ends \
             a factor 1.000e7 apart)"
        );
        let unbounded = Warning::WideInterval {
            parameter: "nu".into(),
            lower: -0.5,
            upper: f64::INFINITY,
            relative_width: f64::INFINITY,
        };
        assert_eq!(
            unbounded.to_string(),
            "nu is poorly determined: its 95 % interval [-0.5000, inf] is wider than its value"
        );
        assert_eq!(number(-2.5), "-2.500");
        assert_eq!(number(0.0), "0");
    }
}
