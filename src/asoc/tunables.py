"""Every tunable of the library: its shipped value, the values it accepts, and why it has it.

:mod:`asoc.config` serves them as ``config.defaults`` (checked when set), ``config.ALLOWED`` and
``config.DESCRIPTIONS``; this module only holds the table, keyed ``"<subpackage>.<name>"``.

Examples
--------
>>> value, allowed, why = TUNABLES["mjls.rank_rtol"]
>>> value, str(allowed)
(1e-10, 'a real number in (0, 1) or None')
"""

import math

from .setting_checks import INT, REAL, REALS, SIZES, Allowed

__all__ = ["TUNABLES"]


#: Each tunable: (shipped value, the values it accepts, why it has that value). Subpackages
#: add their entries here.
TUNABLES: dict[str, tuple[object, Allowed, str]] = {
    "mjls.rank_rtol": (
        1e-10,
        REAL(0, 1, optional=True),
        "Relative singular-value threshold of the minimum-norm solution of (3.51) in Alg. 3.2 "
        "(None: LAPACK's default). "
        "Its matrix becomes singular at the fixed point when the controller state does not "
        "excite every direction; LAPACK's default threshold (about 1e-13 at n = 8) lets rounding "
        "noise into those directions and the iteration diverges (Scaling page, n = 8, 16)."),
    "mjls.matrix_free_min_unknowns": (
        200,
        INT(0),
        "From this many unknowns n^2 + n ny + nu n on, Alg. 3.2 solves (3.51) by matrix-free "
        "conjugate gradients instead of a dense least-squares solve (measured crossover between "
        "195 and 224 unknowns on 2 cores)."),
    "mjls.cg_tolerance": (
        1e-12,
        REAL(0, 1),
        "Relative residual at which each conjugate-gradient solve of (3.51) stops."),
    "mjls.cg_max_iter_factor": (
        10,
        REAL(0, math.inf),
        "Iteration cap of conjugate gradients, as a multiple of the number of unknowns."),
    "mjls.tikhonov_steps": (
        2,
        INT(1),
        "Steps of iterated Tikhonov regularisation in the conjugate-gradient solve of (3.51): one "
        "step leaves a relative bias rcond cond(H), two leave its square."),
    "mjls.dense_max_radius": (
        64,
        INT(0),
        "Up to this size M n^2 the spectral radius comes from the eigenvalues of the dense "
        "Kronecker matrix, above it from Arnoldi (measured crossover on 2 cores)."),
    "mjls.dense_max_solve": (
        256,
        INT(0),
        "Up to this size M n^2 the coupled Lyapunov equations are solved by a dense LU "
        "factorisation, above it iteratively (measured crossover on 2 cores)."),
    "mjls.dense_fallback_radius": (
        1024,
        INT(0),
        "When Arnoldi does not converge: dense eigenvalues up to this M n^2 (0.85 s at 1024), "
        "the cone power method above it."),
    "mjls.arnoldi_subspaces": (
        (60, 150),
        SIZES(2),
        "Krylov-space sizes tried in turn for rho, the next when ARPACK does not converge or its "
        "estimate is not inside a certified bracket of relative width mjls.bracket_warn_rtol: "
        "20 vectors stall on a dominant eigenvalue of multiplicity 4 (the larger-plant page's "
        "chain) or return a subdominant one, 60 converge there in 10 ms; at n = 32, M = 8, 60 "
        "vectors take 0.01 s, 20 vectors 0.15 s (51 products)."),
    "mjls.arnoldi_lean_from": (
        100_000,
        INT(0),
        "From this size M n^2 on, mjls.arnoldi_lean_subspace Krylov vectors are tried before "
        "mjls.arnoldi_subspaces: at n = M = 100 (M n^2 = 10^6) 20 vectors took 21 products "
        "(1.4 s), 60 vectors 61 products and their orthogonalisation (10 s, loaded 2 cores)."),
    "mjls.arnoldi_lean_subspace": (
        8,
        INT(3),
        "The Krylov-space size tried first from M n^2 = mjls.arnoldi_lean_from on. ARPACK's own "
        "work (orthogonalising against the space, restarts) grows with it and there outweighs "
        "the products: at n = M = 100 (rho 0.99, the Alg. 3.1 design) the certified rho took "
        "1.0 s with 8 vectors, 1.1 s with 10 and 1.8 s with 20, to the same bracket."),
    "mjls.arnoldi_lean_tol": (
        1e-10,
        REAL(0, 1),
        "ARPACK's relative accuracy with the Krylov space of mjls.arnoldi_lean_subspace (the "
        "others use mjls.arnoldi_tol). The estimate seeds the certificate, whose bracket is "
        "there as wide as its rounding margin: at n = M = 100 (rho 0.99, the Alg. 3.1 design) "
        "1e-10 took 13 products instead of 17 (0.55 s instead of 0.75 s), to a bracket of the "
        "same relative width, 1.4e-7."),
    "mjls.bracket_rtol": (
        1e-12,
        REAL(0, 1),
        "Relative width of the certified bracket of rho at which its refinement stops (it also "
        "stops where the rounding margin dominates, or when a cone power step narrows it by less "
        "than 10 %)."),
    "mjls.bracket_power_steps": (
        8,
        INT(0),
        "Shifted cone power steps X <- L(X) + rho X that tighten the bracket of rho after the "
        "eigen-solver: each costs one application of L and M Cholesky factorisations; a step "
        "that narrows the bracket by less than 10 % ends them."),
    "mjls.power_max_steps": (
        2000,
        INT(1),
        "Steps of the shifted cone power method where it is the only method (ARPACK failed "
        "above the dense fallback size): the bracket it reaches is reported, undecided if it "
        "straddles 1."),
    "mjls.start_power_steps": (
        30,
        INT(0),
        "Power steps X <- L(X) from a start near the Perron stack (mean_square_stability's "
        "start) before ARPACK: they stop at a change of 1e-10 of the largest entry, or as soon as "
        "their rate says they would not reach it within this many. At n = M = 100 (rho 0.99, "
        "next |lambda| 0.14, the Alg. 3.1 design from its moments) 10 steps give the bracket "
        "of ARPACK's 13 products and their orthogonalisation, in 0.25 s instead of 0.55 s."),
    "mjls.power_tol": (
        1e-13,
        REAL(0, 1),
        "The shifted power method for the left Perron stack stops when an iterate, scaled to "
        "unit largest entry, changes by at most this: a few hundred units of rounding of an "
        "entry of order 1."),
    "mjls.deflated_resolvent_steps": (
        1000,
        INT(1),
        "Iterations for the non-Perron part of the resolvent stack that tightens the upper bound "
        "of rho where the Perron stack is singular "
        "(asoc.mjls.certificate.deflated_resolvent_bounds): they contract at the second-largest "
        "eigenvalue modulus over rho; Alg. 3.2's closed loop at n = 32, M = 8 needs 45 "
        "(0.012 s)."),
    # --- the certified rho (asoc.mjls.stability -> certificate -> spectral_estimate), issue 33
    "mjls.mode_scale_spread": (
        64,
        INT(0),
        "Modes whose scales (largest entry, in powers of 2) differ by more than this many binary "
        "orders are balanced one by one, with the similarity X_i -> 2^t_i X_i that rescales p_ij "
        "by 2^(t_i - t_j); below it one common power of 2 (bit for bit the earlier results). Gains "
        "1e80 and 1e-80 on a 2-cycle (531 orders) made the small mode's A X A^T subnormal under "
        "one common scale, and the bracket wrong."),
    "mjls.mode_balance_sweeps": (
        50,
        INT(1),
        "Sweeps of Osborne's iteration on the log2 weights when modes are balanced one by one; it "
        "stops earlier when a sweep moves no exponent (a 2-cycle needs 2)."),
    "mjls.perron_tie_rtol": (
        1e-8,
        REAL(0, 1),
        "Dense eigenvalues within this relative distance of the largest modulus count as its "
        "ties, among which the real one (the Perron eigenvalue) is taken: periodic chains have "
        "several of equal modulus, computed within a few hundred units of rounding of each other."),
    "mjls.arnoldi_tol": (
        1e-14,
        REAL(0, 1),
        "ARPACK's relative accuracy for the estimate of rho; the estimate only seeds the "
        "certificate, whose bracket (mjls.bracket_rtol) does not depend on it."),
    "mjls.arnoldi_real_rtol": (
        1e-8,
        REAL(0, 1),
        "An Arnoldi eigenvalue of largest modulus whose imaginary part is below this times its "
        "modulus counts as real (the Perron eigenvalue); otherwise the chain is periodic and "
        "Arnoldi is rerun on L + |lambda| I."),
    "mjls.bracket_power_shrink": (
        0.9,
        REAL(0, 1),
        "A cone power step that tightens the bracket of rho must narrow it to below this fraction "
        "of its width, else the steps stop (more of them will not help)."),
    "mjls.lyapunov_certificate_radii": (
        (1.0, 0.5, 0.25),
        REALS(0, 1, closed=True),
        "Where the bracket of rho straddles 1 and rho's estimate rho_hat is below 1, the "
        "Collatz-Wielandt upper bound is also evaluated at the solutions of r X - L(X) = I for "
        "r = rho_hat + f (1 - rho_hat), f from this tuple (f = 1: the Lyapunov certificate "
        "X = L(X) + I of Thm. 3.1). Away from rho the solution is well conditioned even for "
        "defective spectra, where r just above rho is not: a Jordan mode at 0.25 with "
        "off-diagonal 1e3 was bracketed in [0.21, 30.4] from r near rho alone."),
    "mjls.lyapunov_certificate_restarts": (
        5,
        INT(1),
        "Restarts (of 60 GMRES steps) for the Lyapunov certificate's solve above "
        "mjls.dense_fallback_radius (scalar modes: a sparse LU instead), tried only where the "
        "bracket straddles 1: an inexact solution only loosens its bound, and at n = M = 100 "
        "each matrix-vector product costs about 20 ms (300 of them: 6 s)."),
    "mjls.noda_max_steps": (
        60,
        INT(1),
        "Steps of Noda's inverse iteration for scalar modes (n = 1, L an M x M nonnegative sparse "
        "matrix); it converges superlinearly, in under 10 steps on the cyclic chains tested."),
    "mjls.scalar_sparse_from": (
        64,
        INT(0),
        "Scalar modes (n = 1) from this many modes on get rho from Noda's iteration on the sparse "
        "M x M matrix of L (one sparse LU per step), not dense eigenvalues or Arnoldi: 1,100 modes "
        "on a cyclic chain took 88 s and ended undecided with Arnoldi and the power method."),
    "mjls.bracket_warn_rtol": (
        1e-4,
        REAL(0, 1),
        "ms_spectral_radius warns when the certified bracket of rho is relatively wider than "
        "this (defective spectra), and Arnoldi tries its next Krylov space: the pages print rho "
        "to 4 digits. Where the Perron stack is "
        "singular (e.g. triangular modes), the rounding margin alone makes brackets of 1e-5."),
    "mjls.inexact_solve_max": (
        1e-6,
        REAL(0, 1),
        "Loosest relative residual to which Alg. 3.1's exact iteration solves its moment "
        "equations while its gain still moves (it asks for 1e-2 of the gain's last relative "
        "change, down to mjls.solve_tolerance). At n = M = 100 (rho 0.99) its six iterations "
        "take 2.6 s instead of 5.2 s, to the same gain; the Lyapunov certificate of each gain "
        "accounts for the residual."),
    "mjls.solve_residual_max": (
        1e-8,
        REAL(0, 1),
        "Largest relative residual ||X - L(X) - W|| / ||W|| of a coupled Lyapunov solution that is "
        "accepted: an iterative solve above it falls back to a dense solve, or warns; "
        "steady_state_second_moment raises. Four orders above the iterative target, so that "
        "rounding near rho = 1 does not trip it; the failures it catches had 5e3 and 5e4."),
    "mjls.dense_fallback_solve": (
        2048,
        INT(0),
        "Up to this size M n^2 an iterative coupled-Lyapunov solve that misses its residual is "
        "redone by a dense LU factorisation (2048^2 doubles: 32 MB, about 1 s on 2 cores)."),
    "mjls.lmi_equality_rtol": (
        1e-6,
        REAL(0, 1),
        "Largest residual of an LMI problem's equality constraints (e.g. M C_i = C_i G of Thm. "
        "3.9), relative to max(1, largest entry), at which the returned matrices still count as a "
        "certificate: Clarabel's feasibility tolerance is 1e-8, and the gain F M^{-1} stays within "
        "rounding of the exact one far below 1e-6."),
    "mjls.solve_tolerance": (
        1e-12,
        REAL(0, 1),
        "Relative residual ||X - L(X) - W|| / ||W|| at which the iterative coupled-Lyapunov "
        "solve stops."),
    "mjls.divergence_threshold": (
        1e100,
        REAL(1, math.inf),
        "Alg. 3.2 stops as diverged when an entry of its bounds exceeds this: the bounds of a "
        "controller that does not stabilise grow geometrically, and would overflow."),
    "mjls.alg32_max_period": (
        4,
        INT(1),
        "Alg. 3.2 compares its bounds with those of the last this-many iterations: equal to tol "
        "with the previous one means converged, with an earlier one a cycle. The cycles measured "
        "(networked loop of asoc.mjls.examples) have period 2."),
    "mjls.alg31_cycle_window": (
        40,
        INT(2),
        "Iterations (rounded up to a multiple of the period) over which Alg. 3.1's stopping rule "
        "measures how fast its iterates approach a cycle: the change against p iterations back "
        "must fall, over this window, at least twice as fast as the change against the last "
        "one, which must be too slow to reach tol within max_iter. The networked loop of "
        "asoc.mjls.examples approaches its 2-cycle at a rate of about 0.98 per iteration, so the "
        "lag-2 change halves in about 40 iterations while the lag-1 change stays at 0.65."),
    "mjls.alg32_patience": (
        50,
        INT(1),
        "Window w of Alg. 3.2's progress test: it stops without converging (no_progress) when the "
        "smallest relative change of its bounds over the last w iterations is not below that of "
        "the w before, or their ratio predicts that tol is not reached within max_iter. On the "
        "Scaling page's family (n = 16, M = 4) the changes stay between 0.03 and 0.9 for 1,000 "
        "iterations; a slow but converging random system (3 states, 3 modes) needs 1,600 "
        "iterations at a rate of 0.99 per iteration, which the test lets run."),
    "mjls.exact_warm_start_iterations": (
        30,
        INT(0),
        "Iterations of Alg. 3.2 run to start exact_dynamic_output_feedback (with the averaged LQG "
        "compensator as the other candidate). At n = 16, M = 4, 10 and 30 iterations give a start "
        "within 1e-4 of the optimum's cost, so a full run (to 10,000 iterations there) "
        "buys nothing."),
    "mjls.rho_start": (
        0.999,
        REAL(0, 1),
        "The search for a stabilising start of the exact design stops once rho is below this."),
    "mjls.radius_max_iter": (
        1000,
        INT(1),
        "BFGS iterations of a search that minimises rho (stabilising start, min-radius design)."),
    "mjls.lbfgs_memory": (
        200,
        INT(1),
        "Pairs kept by L-BFGS in the exact finite-horizon design "
        "(K (nc^2 + nc ny + nu nc) gains)."),
    "mjls.auto_switch_iterations": (
        200,
        INT(0),
        "Alg. 3.1 with moments='auto' switches from the thesis's iteration to exact moment solves "
        "when its convergence rate predicts more than this many further iterations. Measured on "
        "the Scaling page's family (2 cores, load about 9): n = 16, M = 4, easy (20 iterations): "
        "auto 0.055 s, step 0.063 s, exact 0.46 s; open loop at rho 0.995: step 3.0 s (1,049 "
        "iterations), exact 2.6 s, auto 1.0 s. n = 64, M = 8, easy: auto as step (CPU 0.62-0.69 s "
        "against 0.65-0.74 s); rho 0.995: step 221 s (1,629 iterations), exact 13.3 s, "
        "auto 15.6 s."),
    "mjls.parallel_from": (
        8_000_000,
        INT(0),
        "From this M n^3 on, the products of the moment maps L and L* and of Alg. 3.1's step "
        "(3.35) run in parts of the modes on threads with single-threaded BLAS, and Alg. 3.1's "
        "exact iteration solves its two moment equations at once (asoc.threads.concurrently). "
        "Measured per step of (3.35) on 2 cores, one piece against parts: n = 64, M = 16 "
        "(4.2e6) 1.77 and 1.77 ms; n = 100, M = 16 (1.6e7) 10.2 and 4.8 ms; n = M = 100 58 and "
        "28 ms. Below, waking a thread (about 0.4 ms) costs more than it saves."),
    "mjls.stationary_atol": (
        1e-8,
        REAL(0, 1),
        "Largest |mu_inf T - mu_inf| of a stationary distribution given to MJLS: mu_inf T = mu_inf "
        "to rounding of a probability vector computed elsewhere (e.g. by another library)."),
    "mjls.sampling_time_rtol": (
        1e-12,
        REAL(0, 1),
        "Relative difference at which two sampling times count as one in MJLS.from_statespace and "
        "to_statespace (dt = 0.1 computed two ways differs in the last bits)."),
    "mjls.perron_inner_rtol": (
        1e-12,
        REAL(0, 1),
        "radius_and_gradient: rho is not differentiable where the left and right Perron stacks "
        "are orthogonal (a defective dominant eigenvalue); an inner product below this times "
        "their norms counts as zero, and the gradient is not formed (rounding of the products)."),
    "mjls.lqg_start_regularisation": (
        1e-6,
        REAL(0, 1),
        "Relative diagonal added to V, Q and W of the mode-averaged LQG start of the exact design "
        "(y = C x without noise gives a singular filter Riccati equation): the start only needs "
        "to stabilise, and 1e-6 moves its gains by about that much."),
    "mjls.exact_warm_start_tol": (
        1e-10,
        REAL(0, 1),
        "Tolerance of the short Alg. 3.2 run that starts exact_dynamic_output_feedback (its "
        "iteration cap mjls.exact_warm_start_iterations ends it first in practice)."),
    "mjls.min_radius_tol": (
        1e-12,
        REAL(0, 1),
        "Gradient tolerance of the BFGS search that minimises rho (stabilising start, min-radius "
        "design): it stops earlier once rho < mjls.rho_start, so this only ends a search that "
        "cannot reach it."),
    "optimize.armijo": (
        1e-4,
        REAL(0, 1),
        "Sufficient-decrease constant of the backtracking line search of asoc.optimize.bfgs "
        "(Nocedal and Wright's customary value)."),
    "optimize.min_step": (
        2.0 ** -40,
        REAL(0, 1),
        "The line search of asoc.optimize.bfgs gives up below this step length (then restarts "
        "from a gradient step, or stops with no_progress)."),
    "optimize.curvature_rtol": (
        1e-12,
        REAL(0, 1),
        "asoc.optimize.bfgs skips the inverse-Hessian update unless s'y exceeds this times "
        "|s| |y| (the curvature condition to rounding; Nocedal and Wright, Sec. 6.1)."),
    "linalg.norm_floor": (
        1e-12,
        REAL(0, 1),
        "Absolute floor of ||new|| in asoc.linalg.relative_change: a zero iterate converges "
        "instead of dividing by zero."),
    "gp.gradient_tol": (
        5e-2,
        REAL(0, math.inf),
        "The likelihood maximisation of the GPs of Sec. 2.6 has converged when every component of "
        "the projected gradient of log p(y | X) in log-parameters is below this: a 1 % change of "
        "any hyperparameter then changes log p(y | X) by less than 5e-4 (a likelihood ratio of "
        "1.0005). It is what the computation can reach: with the default bounds cond(Sigma_y) <= "
        "M 1e10, so for M = 200 the gradient's terms of size ~1e2 carry rounding errors of about "
        "cond * eps * 1e2 ~ 4e-2 (the OMAT fits of Sec. 2.6.4 stall at 1e-2 to 4e-2; 1e-2 was "
        "below that)."),
    "gp.quad_epsabs": (
        1e-12,
        REAL(0, 1),
        "Absolute tolerance of scipy.integrate.quad in the density distances and the mCvMd "
        "quadrature of Sec. 2.6 (distances of order 1e-3 to 1 keep 9 digits)."),
    "gp.quad_epsrel": (
        1e-10,
        REAL(0, 1),
        "Relative tolerance of the same quadratures."),
    "gp.max_iterations": (
        500,
        INT(1),
        "Iteration cap of L-BFGS-B per start of the GP likelihood maximisation."),
    "gp.kernel_cache_bytes": (
        64 * 2**20,
        INT(0),
        "Memory for the unit kernel matrices of recent length scales in a GP fit (the kernel "
        "depends on l alone: the optimiser's steps in alpha and sigma_n reuse it)."),
    "gp.mean_kernel_block_rows": (
        10,
        INT(1),
        "Mixtures per block row of the mean kernel (2.22) in MeanKernelGP's likelihood: blocks of "
        "a few MB (200 mixtures of 10 components) that stay in cache."),
    "gp.dirac_max_iterations": (
        1000,
        INT(1),
        "Iteration cap of BFGS in the mCvMd Dirac approximation of N(0, 1) "
        "(it converges in tens)."),
    "gp.max_dirac_components": (
        400,
        INT(1),
        "Largest number of components of the mCvMd Dirac approximation: its gradient holds arrays "
        "of (quadrature nodes) x L x L floats, about 340 MB each at L = 400 with b_max = 100."),
}
