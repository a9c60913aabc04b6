//! The staged solve of the normal equations N x = c, N = AᵀA + εI, of a
//! large sparse least-squares problem whose factor fills in heavily (the
//! vertex flow of Ji et al. 2011, Eq. (20); `crate::enhance`): cheap
//! block-Jacobi conjugate gradients first, conjugate gradients with a
//! problem-specific multigrid preconditioner where those make too little
//! progress, and the sparse Cholesky factorisation as a last resort
//! ([`NormalSolver`]). Every stage starts where the previous one stopped,
//! and all stages give the same solution (to the tolerance of conjugate
//! gradients).

use super::{
    BlockJacobi, CgOptions, CgReport, CholeskySolver, Preconditioner, SolveError, pcg_with,
};
use faer::sparse::SparseColMat;
use serde::Serialize;
use std::time::Instant;

/// Iterations of block-Jacobi conjugate gradients under
/// [`NormalSolver::Auto`] before they switch to the multigrid-preconditioned
/// ones: where the curvature holds every tangential direction (tori of 10k
/// to 1M vertices) block Jacobi converges in about 25 iterations, each
/// cheaper than a preconditioned one and without a setup; where it does not
/// (flat or cylindrical parts) it would need hundreds to thousands.
pub const AUTO_JACOBI_BUDGET: usize = 40;

/// Under [`NormalSolver::Auto`], block-Jacobi conjugate gradients give up
/// early when, every this many iterations, their mean rate over the last
/// ones predicts more than [`AUTO_JACOBI_BUDGET`] iterations
/// ([`CgOptions::hopeless_after`]).
pub const AUTO_JACOBI_CHECK: usize = 4;

/// Largest number of unknown points (3 unknowns each) for which
/// [`NormalSolver::Auto`] falls back to the direct solver when conjugate
/// gradients fail: the Cholesky factor of the vertex flow at 300k vertices
/// takes about 6 GB; beyond, it does not fit a typical machine.
pub const AUTO_DIRECT_LIMIT: usize = 300_000;

/// How the normal equations are solved; all give the same least-squares
/// solution (to the tolerance of conjugate gradients).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum NormalSolver {
    /// [`NormalSolver::Amg`] where the caller knows block Jacobi to be
    /// hopeless ([`StagedOptions::skip_jacobi`]); elsewhere block-Jacobi
    /// conjugate gradients for at most [`AUTO_JACOBI_BUDGET`] iterations
    /// (fewer when their progress predicts far more), then, from where they
    /// stopped, conjugate gradients preconditioned as [`NormalSolver::Amg`]
    /// up to the iteration limit, then (should they fail, and for at most
    /// [`AUTO_DIRECT_LIMIT`] unknown points) the direct solver.
    Auto,
    /// Sparse Cholesky factorisation of the normal matrix AᵀA + εI.
    Direct,
    /// Block-Jacobi preconditioned conjugate gradients on the normal
    /// equations, matrix-free, warm-started at the given guess.
    Cg,
    /// Conjugate gradients preconditioned by block Jacobi plus the
    /// problem's multigrid model, warm-started at the given guess, up to
    /// the iteration limit; an error if they do not converge. Without a
    /// multigrid model it is [`NormalSolver::Cg`].
    Amg,
}

/// The normal equations N x = c of a least-squares problem in blocks of 3
/// unknowns (one point each), as the staged solve sees them.
pub trait NormalEquations {
    /// The right-hand side c (3 entries per point).
    fn rhs(&self) -> &[f64];
    /// out = N v; `scratch` has [`NormalEquations::scratch_len`] entries.
    fn apply(&self, v: &[f64], out: &mut [f64], scratch: &mut [f64]);
    /// Length of the scratch space of [`NormalEquations::apply`].
    fn scratch_len(&self) -> usize;
    /// The 3 × 3 diagonal blocks of N, row-major per point.
    fn diagonal_blocks(&self) -> Vec<f64>;
    /// N assembled (both triangles), for the direct solve.
    fn normal_matrix(&self) -> Result<SparseColMat<usize, f64>, SolveError>;
}

/// Builds the multigrid-preconditioned stage's preconditioner from the
/// block Jacobi of N.
pub type MultigridBuilder<'a> =
    dyn Fn(BlockJacobi) -> Result<Box<dyn Preconditioner + 'a>, SolveError> + 'a;

/// Options of [`StagedSolver::solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct StagedOptions {
    /// The strategy.
    pub solver: NormalSolver,
    /// Under [`NormalSolver::Auto`]: go to the multigrid stage at once (the
    /// caller knows block Jacobi would need far more than
    /// [`AUTO_JACOBI_BUDGET`] iterations).
    pub skip_jacobi: bool,
    /// Conjugate gradients stop at this relative residual. In (0, 1).
    pub tolerance: f64,
    /// Iteration limit of one conjugate-gradient stage. ≥ 1.
    pub max_iterations: usize,
}

impl Default for StagedOptions {
    /// [`NormalSolver::Auto`] with the Jacobi stage, relative residual
    /// 1e-10, at most 1000 iterations per stage.
    fn default() -> Self {
        StagedOptions {
            solver: NormalSolver::Auto,
            skip_jacobi: false,
            tolerance: 1e-10,
            max_iterations: 1000,
        }
    }
}

crate::control::setters!(StagedOptions {
    solver: NormalSolver,
    skip_jacobi: bool,
    tolerance: f64,
    max_iterations: usize,
});

/// What the solves of a [`StagedSolver`] did, summed over its solves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StagedStats {
    /// Conjugate-gradient iterations.
    pub cg_iterations: usize,
    /// Largest final relative residual of the conjugate-gradient runs that
    /// converged (0 when none did).
    pub cg_relative_residual: f64,
    /// Solves of [`NormalSolver::Auto`] that fell back to the direct solve.
    pub direct_fallbacks: usize,
    /// Seconds assembling the normal matrix.
    pub assembly_s: f64,
    /// Seconds building the multigrid preconditioner and factoring N.
    pub factorisation_s: f64,
    /// Seconds in conjugate gradients and triangular solves.
    pub solve_s: f64,
}

/// The staged solver; keeps the symbolic Cholesky analysis between solves
/// of matrices with the same pattern.
#[derive(Default)]
pub struct StagedSolver {
    direct: Option<CholeskySolver>,
    /// What the solves did so far.
    pub stats: StagedStats,
}

impl StagedSolver {
    /// A solver that has not solved anything.
    pub fn new() -> StagedSolver {
        StagedSolver::default()
    }

    /// Solves `system` by the strategy of `options`, starting at `guess`
    /// (3 entries per point). `multigrid` builds the preconditioner of the
    /// multigrid stage; `None` where the problem has none (the stage is
    /// then skipped: [`NormalSolver::Amg`] is block Jacobi, and
    /// [`NormalSolver::Auto`] continues block Jacobi where the direct solve
    /// is too large).
    ///
    /// Errors: conjugate gradients that did not converge under
    /// [`NormalSolver::Cg`], [`NormalSolver::Amg`] or (above
    /// [`AUTO_DIRECT_LIMIT`] points) [`NormalSolver::Auto`]; a multigrid
    /// setup that failed under the same conditions; a failed factorisation.
    pub fn solve(
        &mut self,
        system: &dyn NormalEquations,
        multigrid: Option<&MultigridBuilder<'_>>,
        mut guess: Vec<f64>,
        options: &StagedOptions,
    ) -> Result<Vec<f64>, SolveError> {
        let points = system.rhs().len() / 3;
        let solver = options.solver;
        let not_converged = |r: &CgReport| {
            SolveError::Backend(format!(
                "conjugate gradients did not reach the relative residual {:e} in {} iterations ({:e}); \
                 try the direct solver",
                options.tolerance, r.iterations, r.relative_residual
            ))
        };
        let mut x = None;
        // block-Jacobi CG: alone (Cg, or Amg without a model) or as the
        // cheap first attempt (Auto)
        let jacobi_only =
            solver == NormalSolver::Cg || (solver == NormalSolver::Amg && multigrid.is_none());
        let jacobi_budget = match solver {
            _ if jacobi_only => options.max_iterations,
            NormalSolver::Auto if multigrid.is_some() && options.skip_jacobi => 0,
            NormalSolver::Auto => AUTO_JACOBI_BUDGET.min(options.max_iterations),
            _ => 0,
        };
        let stats = &mut self.stats;
        let mut cg_seconds = 0.0;
        let jacobi = BlockJacobi::from_blocks(system.diagonal_blocks(), 3);
        let mut scratch = vec![0.0; system.scratch_len()];
        // one CG run from `guess`; counts its iterations, time and residual
        let mut run_cg = |guess: &mut [f64],
                          budget: usize,
                          hopeless_after: usize,
                          preconditioner: &dyn Preconditioner,
                          stats: &mut StagedStats|
         -> Result<CgReport, SolveError> {
            let t = Instant::now();
            let r = pcg_with(
                |v: &[f64], out: &mut [f64]| system.apply(v, out, &mut scratch),
                |r: &[f64], z: &mut [f64]| preconditioner.apply(r, z),
                system.rhs(),
                guess,
                &CgOptions {
                    tolerance: options.tolerance,
                    max_iterations: budget,
                    block: 3,
                    hopeless_after,
                },
            )?;
            stats.cg_iterations += r.iterations;
            cg_seconds += t.elapsed().as_secs_f64();
            if r.converged {
                stats.cg_relative_residual = stats.cg_relative_residual.max(r.relative_residual);
            }
            Ok(r)
        };
        if jacobi_budget > 0 {
            let hopeless_after = if jacobi_only { 0 } else { AUTO_JACOBI_CHECK };
            let r = run_cg(&mut guess, jacobi_budget, hopeless_after, &jacobi, stats)?;
            if r.converged {
                x = Some(guess.clone());
            } else if jacobi_only {
                return Err(not_converged(&r));
            }
        }
        // CG preconditioned by the multigrid model, warm-started where block
        // Jacobi stopped
        let staged = matches!(solver, NormalSolver::Amg | NormalSolver::Auto);
        let required = solver == NormalSolver::Amg || points > AUTO_DIRECT_LIMIT;
        if let (None, true, Some(build)) = (&x, staged, multigrid) {
            let t = Instant::now();
            let built = build(jacobi.clone());
            stats.factorisation_s += t.elapsed().as_secs_f64();
            match built {
                Ok(preconditioner) => {
                    let r = run_cg(
                        &mut guess,
                        options.max_iterations,
                        0,
                        preconditioner.as_ref(),
                        stats,
                    )?;
                    if r.converged {
                        x = Some(guess.clone());
                    } else if required {
                        return Err(not_converged(&r));
                    }
                }
                // auto: a degenerate model (e.g. a multigrid level that is
                // not positive definite) leaves the direct solve
                Err(e) if required => return Err(e),
                Err(_) => {}
            }
        }
        if x.is_none() && solver == NormalSolver::Auto && points > AUTO_DIRECT_LIMIT {
            // no model to precondition with; block-Jacobi CG continues (the
            // direct factor does not fit)
            let r = run_cg(&mut guess, options.max_iterations, 0, &jacobi, stats)?;
            if !r.converged {
                return Err(not_converged(&r));
            }
            x = Some(guess.clone());
        }
        stats.solve_s += cg_seconds;
        if let Some(x) = x {
            return Ok(x);
        }
        if jacobi_budget > 0 || staged {
            stats.direct_fallbacks += 1;
        }
        self.direct_solve(system)
    }

    /// The sparse Cholesky solve, reusing the symbolic analysis of the
    /// previous one when the pattern is the same.
    fn direct_solve(&mut self, system: &dyn NormalEquations) -> Result<Vec<f64>, SolveError> {
        let t = Instant::now();
        let matrix = system.normal_matrix()?;
        self.stats.assembly_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let refactored = match self.direct.as_mut() {
            Some(s) => s.refactor(matrix.as_ref()).is_ok(),
            None => false,
        };
        if !refactored {
            self.direct = Some(CholeskySolver::new(matrix.as_ref())?);
        }
        self.stats.factorisation_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x = system.rhs().to_vec();
        if let Some(s) = self.direct.as_ref() {
            s.solve_in_place(&mut x)?;
        }
        self.stats.solve_s += t.elapsed().as_secs_f64();
        Ok(x)
    }
}
