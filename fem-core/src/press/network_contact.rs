//! Contact tools on the Newton path ([`super::network`]): every tool shape and
//! contact law of [`super::contact`], its iteration driving Newton solves.
//!
//! The flat, unrotated, frictionless plates keep the Newton path's own active set
//! (the plate-held `y` dofs cut off the matrix); any other tool runs here.
//!
//! ## Method
//!
//! The contact iteration is the linear chain's ([`ContactModel::settle`]): the
//! statuses, the augmented Lagrangian with its Uzawa updates, Coulomb's return
//! map with stick predictor and slip history, glued anchors, the release, the
//! closest points and normals of the tool shapes ([`super::tools`]), and the
//! [`super::ToolSample`] output. Each of its solves asks for the displacement
//! under given node penalties or given held dofs; here that solve is Newton's
//! iteration of the finite-strain step:
//!
//! - **Penalties** (curved or rotated tools, friction, glue next to a curved
//!   tool): the iteration asks for `u` with `(A + P) u = b + r`, where `P` holds
//!   the active nodes' `D x D` blocks (`k n n^T` for normal contact, `k I` when
//!   stuck or glued; in the node's own diagonal block, already in the pattern)
//!   and `r = F(u_old) + P u_old` carries the contact forces `F` at the last
//!   iterate. On the Newton path `A u - b` is the out-of-balance force
//!   `f_int(u) - f_body`, so the solve is Newton on
//!   `f_body + r - P u - f_int(u) = 0` with the tangent `K(u) + P`. The penalty
//!   forces are evaluated as `(r - P u_ref) - P (u - u_ref)` from the solve's
//!   start `u_ref`: written as `r - P u` their rounding (`eps k |u|`, with `k` a
//!   million times the node's stiffness) would sit at Newton's tolerance.
//! - **Held dofs** (flat unrotated plates that are glued, beside frictionless
//!   ones, with no curved tool engaged): the exact elimination of
//!   [`super::contact`], "Flat tools": the dofs are held at their values (cut
//!   off the matrix, as the Newton path's own plates are) and their reactions
//!   `f_int - f_body` are the multipliers.
//!
//! A curved tool's normals turn with the node; the iteration takes Newton steps
//! on the contact forces until the displacement settles (the chain's "Curved
//! tools"), each a converged finite-strain solve. The low-rank path of the chain
//! is off: the finite-strain tangent changes from solve to solve.
//!
//! ## Failures
//!
//! A Newton solve that does not converge, a law that fails or a contact that
//! does not settle fails the step attempt; the stepper retries it shorter and
//! names the step, the time and the element or tool when it cannot.

use std::cell::RefCell;

use super::contact::{ContactModel, ContactState, Settled, StepInput};
use super::network::{Converged, StepFailure};
use super::{PressError, PressProblem};
use crate::assembly::CsrPattern;
use crate::element::{ReferenceSimplex, Simplex};

/// Node penalties added to a Newton solve: the matrix term `P` and the force
/// `(r - P u_ref) - P (u - u_ref)` (see the module docs, "Penalties").
pub(super) struct Penalty {
    /// `P` on the pattern's values.
    pub values: Vec<f64>,
    /// `r - P u_ref` per dof [N].
    base: Vec<f64>,
    /// `u_ref` [mm].
    reference: Vec<f64>,
}

impl Penalty {
    /// Adds the contact forces on the specimen at `u` to `out` (per dof) [N].
    pub fn add_forces(&self, pattern: &CsrPattern, u: &[f64], out: &mut [f64]) {
        let step: Vec<f64> = u.iter().zip(&self.reference).map(|(a, b)| a - b).collect();
        let mut pu = vec![0.0; u.len()];
        pattern.mul_vec(&self.values, &step, &mut pu);
        for ((o, b), p) in out.iter_mut().zip(&self.base).zip(&pu) {
            *o += b - p;
        }
    }

    /// The rounding of the residual's norm at `u` [N]: a penalized dof's force
    /// `k (u - u_ref)` carries `eps k |u|`, with `k` a million times the node's
    /// stiffness about 1e-10 of its force, at Newton's tolerance; Newton stops
    /// there (16 times it: the sums of the force and of its rounding).
    pub fn rounding(&self, diagonal_positions: &[usize], u: &[f64]) -> f64 {
        let sum: f64 = diagonal_positions.iter().zip(u).map(|(&p, x)| (self.values[p] * x.abs()).powi(2)).sum();
        16.0 * f64::EPSILON * sum.sqrt()
    }
}

/// A Newton solve of the step: the penalties (or none), the dofs held at given
/// values beside the support's, and the start; returns the converged step.
pub(super) type NewtonSolve<'a> =
    dyn FnMut(Option<&Penalty>, &[(usize, f64)], Vec<f64>) -> Result<Converged, StepFailure> + 'a;

/// One step's data for the contact iteration.
pub(super) struct ContactStep<'a> {
    /// The step's start and end [s].
    pub t0: f64,
    pub t1: f64,
    /// The step's number (errors).
    pub step: usize,
    /// The displacement at the step's start [mm].
    pub u_start: &'a [f64],
    /// The tangent's diagonal per dof at the step's start [N/mm] (the penalties' scale).
    pub diagonal: &'a [f64],
    /// The body force per dof [N].
    pub body_force: &'a [f64],
    /// The dofs the support holds (their reactions are not contact forces).
    pub held: &'a [bool],
    /// The step matrix's pattern.
    pub pattern: &'a CsrPattern,
}

/// The tools of a Newton-path problem and their contact iteration.
pub(super) struct NetworkContact<'t> {
    contact: ContactModel<'t>,
    /// Node positions at rest [mm].
    rest: Vec<Vec<f64>>,
    nnz: usize,
}

impl<'t> NetworkContact<'t> {
    /// The contact model of `problem`'s tools; `held` marks the support's dofs.
    pub fn new<const D: usize, const N: usize, const S: usize>(
        problem: &'t PressProblem<D, N, S>,
        pattern: &CsrPattern,
        held: &[bool],
    ) -> Result<Self, PressError>
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let mut contact = ContactModel::new(problem, pattern, held)?;
        contact.low_rank = false;
        let rest = problem.mesh.nodes.iter().map(|p| p.to_vec()).collect();
        Ok(Self { contact, rest, nnz: pattern.nnz() })
    }

    /// No node in contact.
    pub fn initial_state(&self) -> ContactState {
        self.contact.initial_state()
    }

    /// Settles one step from `state0` (the contact state at the step's start)
    /// and the Newton start `u_guess`: the converged step at the settled contact,
    /// and the contact's new state and samples (listed order). Nothing is
    /// committed: the caller keeps the state when it accepts the step.
    pub fn settle(
        &self,
        step: &ContactStep<'_>,
        state0: &ContactState,
        u_guess: Vec<f64>,
        solve: &mut NewtonSolve<'_>,
    ) -> Result<(Converged, Settled), StepFailure> {
        let input = StepInput {
            t0: step.t0,
            t1: step.t1,
            step: step.step,
            rest: &self.rest,
            diagonal: step.diagonal,
            u0: step.u_start,
            factor_key: 0,
            scale: 1.0,
            lift: [0.0; 2],
        };
        // The last converged solve (the settled step is the iteration's last
        // solve) and why a solve failed, kept apart from the iteration's error.
        let last: RefCell<Option<Converged>> = RefCell::new(None);
        let failed: RefCell<Option<StepFailure>> = RefCell::new(None);
        let solve = RefCell::new(solve);
        let start = |held: &[(usize, f64)]| {
            let mut u = last.borrow().as_ref().map_or_else(|| u_guess.clone(), |c| c.u.clone());
            held.iter().for_each(|&(d, v)| u[d] = v);
            u
        };
        let run = |penalty: Option<&Penalty>, held: &[(usize, f64)], u: Vec<f64>| {
            let solved = (*solve.borrow_mut())(penalty, held, u);
            match solved {
                Ok(c) => {
                    let u = c.u.clone();
                    *last.borrow_mut() = Some(c);
                    Ok(u)
                }
                Err(f) => {
                    *failed.borrow_mut() = Some(f);
                    Err(PressError::BadSettings("a Newton solve of the contact iteration failed".into()))
                }
            }
        };
        let mut penalized = |_hash: u64, values: &dyn Fn() -> Vec<f64>, extra: &[f64], columns: Option<usize>| {
            debug_assert!(columns.is_none(), "the low-rank path is off on the Newton path");
            let reference = start(&[]);
            let values = values();
            let mut pu = vec![0.0; reference.len()];
            step.pattern.mul_vec(&values, &reference, &mut pu);
            let base = extra.iter().zip(&pu).map(|(r, p)| r - p).collect();
            let penalty = Penalty { values, base, reference: reference.clone() };
            run(Some(&penalty), &[], reference)
        };
        let mut eliminated = |_hash: u64, held: &[(usize, f64)]| {
            let u = run(None, held, start(held))?;
            let c = last.borrow();
            let internal = &c.as_ref().expect("set by the solve").internal;
            let reactions = held.iter().map(|&(d, _)| internal[d] - step.body_force[d]).collect();
            Ok((u, reactions))
        };
        let settled = self.contact.settle(&input, state0, u_guess.clone(), &mut penalized, &mut eliminated, self.nnz);
        match settled {
            Ok(mut s) => {
                let c = last.into_inner().expect("a contact step solves at least once");
                // The tool forces as the equilibrium's reactions: what the free
                // rows leave unbalanced against the contact forces (the
                // multipliers' and the penalties' rounding, up to the
                // contact iteration's tolerance) moves into the tools.
                let imbalance: Vec<f64> = (0..c.internal.len())
                    .map(|d| if step.held[d] { 0.0 } else { c.internal[d] - step.body_force[d] - s.forces[d] })
                    .collect();
                self.contact.rebalance(&mut s, &imbalance);
                Ok((c, s))
            }
            Err(e) => Err(failed.into_inner().unwrap_or(StepFailure::Contact(e))),
        }
    }
}
