//! Mullins-type damage campaigns of the blind self-check, diagnosed one by one
//! (`wagashi diagnose --blind` has no case filter): campaign `i` of
//! `blind_mullins SEED L0 L1 ...` withholds `mullins-damage` at target strength
//! `Li`, with the seed `campaign_seed(SEED, i)`, the issue's scatter and the blind
//! check's default options, exactly as `run_blind` would run that case list.
//! Prints the realised strength, the verdict, the five candidates of the largest
//! likelihood ratio and the flagged cells.
//!
//! ```text
//! cargo run --release -p wagashi-calibrate --example blind_mullins -- 101 30 100 300
//! ```
//!
//! Figures: calibrate/src/diagnosis/blind.rs, module docs.

use calibrate::diagnosis::blind::{campaign_seed, default_options, run_case, Case, OutOfLibrary, Scatter, Truth};

fn main() {
    let mut args = std::env::args().skip(1);
    let seed: u64 = match args.next().map(|s| s.parse()) {
        None => 101,
        Some(Ok(s)) => s,
        Some(Err(e)) => {
            eprintln!("the seed must be an integer: {e}");
            std::process::exit(2);
        }
    };
    let lambdas: Result<Vec<f64>, _> = args.map(|s| s.parse::<f64>()).collect();
    let lambdas = match lambdas {
        Ok(l) if l.is_empty() => vec![30.0, 100.0, 300.0],
        Ok(l) => l,
        Err(e) => {
            eprintln!("the strengths must be numbers: {e}");
            std::process::exit(2);
        }
    };
    let options = default_options(seed);
    for (i, &lambda) in lambdas.iter().enumerate() {
        let case = Case { truth: Truth::OutOfLibrary(OutOfLibrary::MullinsDamage), lambda };
        let s = campaign_seed(seed, i);
        let (o, d) = match run_case(i, &case, s, &Scatter::ISSUE, &options) {
            Ok(x) => x,
            Err(e) => {
                println!("campaign {i}, lambda {lambda}: failed: {e}");
                continue;
            }
        };
        let g = &o.generated;
        println!(
            "campaign {i}, lambda {lambda}: {:?}, lambda_eff {:.1} (reached {}) -> `{}` ({:.0} s + {:.0} s)",
            g.strength, g.lambda_eff, g.reached, o.label, o.generate_s, o.diagnose_s
        );
        let mut candidates: Vec<_> = d.candidates.iter().collect();
        candidates.sort_by(|a, b| b.lr.total_cmp(&a.lr));
        for c in candidates.iter().take(5) {
            println!(
                "    {}: LR {:.1} (critical {:.1}), held-out closure {:?}, cells left flagged {:?}",
                c.effect,
                c.lr,
                c.lr_critical,
                c.heldout.as_ref().map(|h| h.closure),
                c.remaining_flagged
            );
        }
        let flagged: Vec<String> = d
            .where_cells
            .iter()
            .filter(|c| c.flagged)
            .map(|c| format!("{:?}/{:?}/{:?}", c.phase, c.channel, c.region))
            .collect();
        println!("    flagged cells {flagged:?}; {}", d.verdict.sentence);
    }
}
