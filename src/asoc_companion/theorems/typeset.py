"""The theorems study's plain-text descriptions typeset for the Theorems page: the same words,
their math in LaTeX (MyST Markdown, ``$...$``), keyed by the text the study records.

A text the study changes is no longer found here and is shown as recorded (plain text);
tests/companion/test_theorems_page.py lists the records without a typeset form. The diagnoses
(theorems.corrections) are written in LaTeX where they are made, their numbers by
:func:`number_tex` and :func:`matrix_tex`.
"""

__all__ = ["MUTANTS_TEX", "CORRECTIONS_TEX", "CHECKS_TEX", "number_tex", "matrix_tex"]


def number_tex(value, spec="") -> str:
    r"""``value`` formatted with the Python format ``spec`` (``str`` without one), as LaTeX math:
    an exponent ``e-14`` becomes ``\cdot10^{-14}`` (the diagnoses of theorems.corrections).

    Examples
    --------
    >>> number_tex(4.268807529683727e-14, ".1e"), number_tex(7e-15, ".0e"), number_tex(0.0001, "g")
    ('4.3\\cdot10^{-14}', '7\\cdot10^{-15}', '0.0001')
    >>> number_tex("1e-4"), number_tex(-0.272, ".3f"), number_tex(0.0, ".1e")
    ('10^{-4}', '-0.272', '0')
    """
    text = format(value, spec) if spec else str(value)
    if "e" not in text:
        return text
    mantissa, exponent = text.split("e")
    if float(mantissa) == 0:
        return "0"
    power = f"10^{{{int(exponent)}}}"
    return power if float(mantissa) == 1 else rf"{mantissa}\cdot{power}"


def matrix_tex(rows, spec="") -> str:
    r"""A matrix given as a list of rows, its entries by :func:`number_tex`, as a LaTeX ``bmatrix``.

    Examples
    --------
    >>> matrix_tex([[0.3364, 0.1107], [-1.3845, -0.4556]])
    '\\begin{bmatrix}0.3364&0.1107\\\\-1.3845&-0.4556\\end{bmatrix}'
    """
    body = r"\\".join("&".join(number_tex(v, spec) for v in row) for row in rows)
    return rf"\begin{{bmatrix}}{body}\end{{bmatrix}}"


MUTANTS_TEX = {
    "the reference without the measurement update (the prediction P: the Schur complement dropped)":
        r"the reference without the measurement update (the prediction $\mathbf P$: the Schur "
        r"complement dropped)",
    "the expansion with x^T V_K x in place of 1/2 x^T V_K x (a factor changed)":
        r"the expansion with $\mathbf x^\top\mathbf V_K\mathbf x$ in place of "
        r"$\tfrac12\mathbf x^\top\mathbf V_K\mathbf x$ (a factor changed)",
    "the exact costs without the innovation's share P_k - Sigma_{k+1} of the estimate's second "
    "moment":
        r"the exact costs without the innovation's share $\mathbf P_k-\boldsymbol\Sigma_{k+1}$ of "
        r"the estimate's second moment",
    "the covariance exp(-(d/l)^4), outside Table 2.1 and not positive definite even on the real "
    "line":
        r"the covariance $\exp(-(d/l)^4)$, outside Table 2.1 and not positive definite even on the "
        r"real line",
    "the premise negated: a solution with an eigenvalue <= 0 in both forms 'implies' stability":
        r"the premise negated: a solution with an eigenvalue $\leq 0$ in both forms 'implies' "
        r"stability",
    "the formula with D_i in place of D_i + E_i L_i C_i":
        r"the formula with $\mathbf D_i$ in place of $\mathbf D_i+\mathbf E_i\mathbf L_i\mathbf "
        r"C_i$",
    "the BMI with its corner block G_i + G_i^T in place of G_i + G_i^T - D_i(Y)":
        r"the BMI with its corner block $\mathbf G_i+\mathbf G_i^\top$ in place of "
        r"$\mathbf G_i+\mathbf G_i^\top-\mathcal D_i(\mathbf Y)$",
    "the gains recovered with a sign error, L_i = -F_i M_i^{-1}":
        r"the gains recovered with a sign error, $\mathbf L_i=-\mathbf F_i\mathbf M_i^{-1}$",
    "the recursion without the noise term mu_k^i H_i H_i^T":
        r"the recursion without the noise term $\mu_k^i\mathbf H_i\mathbf H_i^\top$",
    "the corrected reading with X_inf solved without the noise term":
        r"the corrected reading with $\mathbf X_\infty$ solved without the noise term",
    "the stated form without the noise term mu_i H_i H_i^T":
        r"the stated form without the noise term $\mu_i\mathbf H_i\mathbf H_i^\top$",
    "the residual of (3.31) without R_i": r"the residual of (3.31) without $\mathbf R_i$",
    "the formula with 2 R_i in place of R_i":
        r"the formula with $2\mathbf R_i$ in place of $\mathbf R_i$",
    "M / 2 in place of M (a factor changed: 'rho(M) < 2 implies stability')":
        r"$\mathbf M/2$ in place of $\mathbf M$ (a factor changed: '$\rho(\mathbf M)<2$ implies "
        r"stability')",
    "Q~ = diag(Q, R) (the gain L dropped)":
        r"$\tilde{\mathbf Q}=\mathrm{diag}(\mathbf Q,\mathbf R)$ (the gain $\mathbf L$ dropped)",
    "the recursion without the process noise mu_k^i H_i H_i^T":
        r"the recursion without the process noise $\mu_k^i\mathbf H_i\mathbf H_i^\top$",
    "Q~ without the input's block L^T R_i L":
        r"$\tilde{\mathbf Q}$ without the input's block $\mathbf L^\top\mathbf R_i\mathbf L$",
    "the stated form without the noise term mu_i H~_i H~_i^T":
        r"the stated form without the noise term $\mu_i\tilde{\mathbf H}_i\tilde{\mathbf "
        r"H}_i^\top$",
    "the solution's L scaled by 1.2": r"the solution's $\mathbf L$ scaled by 1.2",
    "the recursion without the noise term omega": r"the recursion without the noise term $\omega$",
    "the hypotheses A, B >= 0 dropped (A, B symmetric indefinite)":
        r"the hypotheses $\mathbf A,\mathbf B\geq 0$ dropped ($\mathbf A$, $\mathbf B$ symmetric "
        r"indefinite)",
    "Jbar_0 without the noise's share omega":
        r"$\bar{\mathcal J}_0$ without the noise's share $\omega$",
    "the formula with D_i in place of D_i + E_i L C_i (the input's share of z dropped)":
        r"the formula with $\mathbf D_i$ in place of $\mathbf D_i+\mathbf E_i\mathbf L\mathbf C_i$ "
        r"(the input's share of $\mathbf z$ dropped)",
    "the BMI with its corner block G + G^T in place of G + G^T - D_i(Y)":
        r"the BMI with its corner block $\mathbf G+\mathbf G^\top$ in place of "
        r"$\mathbf G+\mathbf G^\top-\mathcal D_i(\mathbf Y)$",
    "the gain recovered with a sign error, L = -F M^{-1}":
        r"the gain recovered with a sign error, $\mathbf L=-\mathbf F\mathbf M^{-1}$",
    "the closed form without Delta (the noise's cost dropped)":
        r"the closed form without $\Delta$ (the noise's cost dropped)",
    "the limit compared with the LQ gain for 2 R instead of R":
        r"the limit compared with the LQ gain for $2\mathbf R$ instead of $\mathbf R$",
    "the comparison with the LQG controller for 2 R instead of R":
        r"the comparison with the LQG controller for $2\mathbf R$ instead of $\mathbf R$",
    "the printed Hellinger expression (1 - BC)^2 as D, with the same covariances and length scales":
        r"the printed Hellinger expression $(1-\mathrm{BC})^2$ as $D$, with the same covariances "
        r"and length scales",
    "(B.4) with the factor 2 of 2 E(Pbar + Pu) B L Xu A^T dropped":
        r"(B.4) with the factor 2 of $2\,\mathcal E(\bar{\mathbf P}+\underline{\mathbf P})\mathbf "
        r"B\mathbf L\underline{\mathbf X}\mathbf A^\top$ dropped",
    'T transposed in both Lyapunov equations (on 3 modes, 2-3 states, T near a 3-cycle run in '
    'the direction where the transposition understates the radius: with n_x = 1 or M = 2 the '
    'spectra coincide, and reversing the cycle is what T^T does)':
        r"$\mathbf T$ transposed in both Lyapunov equations (on 3 modes, 2-3 states, $\mathbf "
        r"T$ near a 3-cycle run in the direction where the transposition understates the radius: "
        r"with $n_x=1$ or $M=2$ the spectra coincide, and reversing the cycle is what $\mathbf "
        r"T^\top$ does)",
    "M built with T in place of T^T (T transposed; draws as for Thm. 3.1's mutant)":
        r"$\mathbf M$ built with $\mathbf T$ in place of $\mathbf T^\top$ ($\mathbf T$ "
        r"transposed; draws as for Thm. 3.1's mutant)",
    'the hypotheses A, B >= 0 dropped (A, B = psd - 4 psd, mostly negative)':
        r"the hypotheses $\mathbf A,\mathbf B\geq 0$ dropped ($\mathbf A$, $\mathbf B$ = psd "
        r"$-\,4$ psd, mostly negative)",
}
"""The mutants' descriptions (plain text in the study's records) with their math in LaTeX; a
description not listed is shown as recorded."""


CORRECTIONS_TEX = {
    "If D embeds isometrically in a Hilbert space (mCvMd, the L2 distance of densities, the "
    "Hellinger distance sqrt(1 - int sqrt(p1 p2))), every covariance of Table 2.1 (gamma <= 2) of "
    "Delta = D is positive semidefinite at every length scale. Proof: each is a scale mixture int "
    "exp(-t Delta^2) dmu(t) (t Delta^2 for SE, Gamma mixtures for RQ and Matern, Bernstein's "
    "theorem for exp(-(Delta/l)^gamma)), and exp(-t D^2) is PSD for all t > 0 iff D^2 is "
    "conditionally negative definite, i.e. D is Hilbertian (Schoenberg).":
        r"If $D$ embeds isometrically in a Hilbert space (mCvMd, the $L_2$ distance of densities, "
        r"the Hellinger distance $\sqrt{1-\int\sqrt{p_1p_2}}$), every covariance of Table 2.1 "
        r"($\gamma\leq2$) of $\Delta=D$ is positive semidefinite at every length scale. Proof: "
        r"each is a scale mixture $\int e^{-t\Delta^2}\,\mathrm d\mu(t)$ ($t\Delta^2$ for SE, "
        r"Gamma mixtures for RQ and Matérn, Bernstein's theorem for $e^{-(\Delta/l)^\gamma}$), and "
        r"$e^{-tD^2}$ is PSD for all $t>0$ iff $D^2$ is conditionally negative definite, i.e. $D$ "
        r"is Hilbertian (Schoenberg).",
    "If M = 1 and C = I (state feedback), (A, B) is stabilisable and Q > 0, Alg. 3.1 converges "
    "from every X_0 > 0, P_0 >= 0 to the LQ gain. Proof: with one mode and C = I the X-factors "
    "cancel in (3.34), L = -(R + B^T P B)^{-1} B^T P A, so (3.35) for P is the Riccati value "
    "iteration, which converges to the stabilising solution (Kalman; Bertsekas, Vol. 1, Prop. "
    "4.4.1); X then follows a converging Lyapunov recursion.":
        r"If $M=1$ and $\mathbf C=\mathbf I$ (state feedback), $(\mathbf A,\mathbf B)$ is "
        r"stabilisable and $\mathbf Q>0$, Alg. 3.1 converges from every $\mathbf X_0>0$, $\mathbf "
        r"P_0\geq0$ to the LQ gain. Proof: with one mode and $\mathbf C=\mathbf I$ the $\mathbf "
        r"X$-factors cancel in (3.34), $\mathbf L=-(\mathbf R+\mathbf B^\top\mathbf P\mathbf "
        r"B)^{-1}\mathbf B^\top\mathbf P\mathbf A$, so (3.35) for $\mathbf P$ is the Riccati value "
        r"iteration, which converges to the stabilising solution (Kalman; Bertsekas, Vol. 1, Prop. "
        r"4.4.1); $\mathbf X$ then follows a converging Lyapunov recursion.",
    "X~_inf <= 2 [[Xbar + Xu, Xu], [Xu, Xu]] and P~_inf <= 2 [[Pbar + Pu, -Pu], [-Pu, Pu]] with "
    "Xbar = X1 - X12 - X12^T + X2, Xu = X2, Pbar = P1 + P12 + P12^T + P2, Pu = P2. Proof: with e "
    "= x - x^, [x; x^] = [e; 0] + [x^; x^] and (a + b)(a + b)^T <= 2 a a^T + 2 b b^T; for P~, z = "
    "[x; x] + [0; -e] in z^T P~ z <= 2 (.) + 2 (.). (For P the cross terms enter Pbar with +, not "
    "- as printed.)":
        r"$\tilde{\mathbf X}_\infty\preceq2\begin{bmatrix}\bar{\mathbf X}+\underline{\mathbf "
        r"X}&\underline{\mathbf X}\\\underline{\mathbf X}&\underline{\mathbf X}\end{bmatrix}$ and "
        r"$\tilde{\mathbf P}_\infty\preceq2\begin{bmatrix}\bar{\mathbf P}+\underline{\mathbf "
        r"P}&-\underline{\mathbf P}\\-\underline{\mathbf P}&\underline{\mathbf P}\end{bmatrix}$ "
        r"with $\bar{\mathbf X}=\mathbf X_1-\mathbf X_{12}-\mathbf X_{12}^\top+\mathbf X_2$, "
        r"$\underline{\mathbf X}=\mathbf X_2$, $\bar{\mathbf P}=\mathbf P_1+\mathbf P_{12}+\mathbf "
        r"P_{12}^\top+\mathbf P_2$, $\underline{\mathbf P}=\mathbf P_2$. Proof: with $\mathbf "
        r"e=\mathbf x-\hat{\mathbf x}$, $[\mathbf x;\hat{\mathbf x}]=[\mathbf e;\mathbf "
        r"0]+[\hat{\mathbf x};\hat{\mathbf x}]$ and $(\mathbf a+\mathbf b)(\mathbf a+\mathbf "
        r"b)^\top\preceq2\mathbf a\mathbf a^\top+2\mathbf b\mathbf b^\top$; for $\tilde{\mathbf "
        r"P}$, $\mathbf z=[\mathbf x;\mathbf x]+[\mathbf 0;-\mathbf e]$ in $\mathbf "
        r"z^\top\tilde{\mathbf P}\mathbf z\leq2(\cdot)+2(\cdot)$. (For $\mathbf P$ the cross terms "
        r"enter $\bar{\mathbf P}$ with $+$, not $-$ as printed.)",
    "For M = 1: a solution of (3.45)-(3.49) with invertible Xu and E(Pu) whose controller "
    "stabilises is the LQG controller, the optimum of (3.38). Proof: the F-row of (3.49) reads "
    "E(Pu)(F + K C - B L - A) Xu = 0, so F = A + B L - K C; then the K-row gives K = A Xbar C^T "
    "(C Xbar C^T + J J^T)^{-1} and (3.45) the filter Riccati equation, the L-row L = -(R + B^T "
    "Pbar B)^{-1} B^T Pbar A and (3.47) the control Riccati equation; the closed loop's "
    "eigenvalues are those of A + B L and A - K C, so Xbar and Pbar are the stabilising (unique) "
    "solutions. Checked: the exact cost of Alg. 3.2's converged, stabilising controller equals "
    "the LQG cost.":
        r"For $M=1$: a solution of (3.45)-(3.49) with invertible $\underline{\mathbf X}$ and "
        r"$\mathcal E(\underline{\mathbf P})$ whose controller stabilises is the LQG controller, "
        r"the optimum of (3.38). Proof: the $\mathbf F$-row of (3.49) reads $\mathcal "
        r"E(\underline{\mathbf P})(\mathbf F+\mathbf K\mathbf C-\mathbf B\mathbf L-\mathbf "
        r"A)\underline{\mathbf X}=\mathbf 0$, so $\mathbf F=\mathbf A+\mathbf B\mathbf L-\mathbf "
        r"K\mathbf C$; then the $\mathbf K$-row gives $\mathbf K=\mathbf A\bar{\mathbf X}\mathbf "
        r"C^\top(\mathbf C\bar{\mathbf X}\mathbf C^\top+\mathbf J\mathbf J^\top)^{-1}$ and (3.45) "
        r"the filter Riccati equation, the $\mathbf L$-row $\mathbf L=-(\mathbf R+\mathbf "
        r"B^\top\bar{\mathbf P}\mathbf B)^{-1}\mathbf B^\top\bar{\mathbf P}\mathbf A$ and (3.47) "
        r"the control Riccati equation; the closed loop's eigenvalues are those of $\mathbf "
        r"A+\mathbf B\mathbf L$ and $\mathbf A-\mathbf K\mathbf C$, so $\bar{\mathbf X}$ and "
        r"$\bar{\mathbf P}$ are the stabilising (unique) solutions. Checked: the exact cost of "
        r"Alg. 3.2's converged, stabilising controller equals the LQG cost.",
    "J_0 <= sum_k sum_i 2 tr[Q_i (Xbar_k + Xu_k) + L_k^T R_i L_k Xu_k] (+ the final term), with "
    "(3.66)-(3.67) whose two transported terms are doubled, started at the exact Xbar_0 = "
    "E{e_0 e_0^T}, Xu_0 = E{x^_0 x^_0^T}. Proof: e_{k+1} = (A - K C) e + (A - F + B L - K C) x^ + "
    "H w - K J v and x^_{k+1} = K C e + (F + K C) x^ + K J v; (a + b)(a + b)^T <= 2 a a^T + 2 b "
    "b^T and monotonicity give the blocks' bounds by induction, and Prop. 3.26 corrected gives "
    "X~_k <= 2 [[Xbar + Xu, Xu], [Xu, Xu]]. Valid, but loose: the factor 2 compounds over the "
    "horizon.":
        r"$\mathcal J_0\leq\sum_k\sum_i2\,\mathrm{tr}[\mathbf Q_i(\bar{\mathbf "
        r"X}_k+\underline{\mathbf X}_k)+\mathbf L_k^\top\mathbf R_i\mathbf L_k\underline{\mathbf "
        r"X}_k]$ (+ the final term), with (3.66)-(3.67) whose two transported terms are doubled, "
        r"started at the exact $\bar{\mathbf X}_0=\mathrm E\{\mathbf e_0\mathbf e_0^\top\}$, "
        r"$\underline{\mathbf X}_0=\mathrm E\{\hat{\mathbf x}_0\hat{\mathbf x}_0^\top\}$. Proof: "
        r"$\mathbf e_{k+1}=(\mathbf A-\mathbf K\mathbf C)\mathbf e+(\mathbf A-\mathbf F+\mathbf "
        r"B\mathbf L-\mathbf K\mathbf C)\hat{\mathbf x}+\mathbf H\mathbf w-\mathbf K\mathbf "
        r"J\mathbf v$ and $\hat{\mathbf x}_{k+1}=\mathbf K\mathbf C\mathbf e+(\mathbf F+\mathbf "
        r"K\mathbf C)\hat{\mathbf x}+\mathbf K\mathbf J\mathbf v$; $(\mathbf a+\mathbf b)(\mathbf "
        r"a+\mathbf b)^\top\preceq2\mathbf a\mathbf a^\top+2\mathbf b\mathbf b^\top$ and "
        r"monotonicity give the blocks' bounds by induction, and Prop. 3.26 corrected gives "
        r"$\tilde{\mathbf X}_k\preceq2\begin{bmatrix}\bar{\mathbf X}+\underline{\mathbf "
        r"X}&\underline{\mathbf X}\\\underline{\mathbf X}&\underline{\mathbf X}\end{bmatrix}$. "
        r"Valid, but loose: the factor 2 compounds over the horizon.",
    "For PSD Xbar_k, Xu_k, E(Pbar_{k+1}), E(Pu_{k+1}), the solutions of (3.70) are the minimisers "
    "of (B.4) over (F_k, K_k, L_k). Proof: the quadratic part of (B.4) is sum_i tr[E(Pu)(K C + F "
    "- B L) Xu (.)^T + E(Pu) K C Xbar C^T K^T + E(Pbar) B L Xu L^T B^T + L^T R L Xu + mu E(Pu) K "
    "J J^T K^T] >= 0, so (B.4) is convex, and its gradient is twice the residual of (3.70) (B.5).":
        r"For PSD $\bar{\mathbf X}_k$, $\underline{\mathbf X}_k$, $\mathcal E(\bar{\mathbf "
        r"P}_{k+1})$, $\mathcal E(\underline{\mathbf P}_{k+1})$, the solutions of (3.70) are the "
        r"minimisers of (B.4) over $(\mathbf F_k,\mathbf K_k,\mathbf L_k)$. Proof: the quadratic "
        r"part of (B.4) is "
        # one formula per term: the sum breaks between them on a narrow page
        r"$\sum_i\mathrm{tr}[\mathcal E(\underline{\mathbf P})(\mathbf K\mathbf C+\mathbf "
        r"F-\mathbf B\mathbf L)\underline{\mathbf X}(\cdot)^\top$ $+\,\mathcal "
        r"E(\underline{\mathbf P})\mathbf K\mathbf C\bar{\mathbf X}\mathbf C^\top\mathbf K^\top$ "
        r"$+\,\mathcal E(\bar{\mathbf P})\mathbf B\mathbf L\underline{\mathbf X}\mathbf "
        r"L^\top\mathbf B^\top$ $+\,\mathbf L^\top\mathbf R\mathbf L\underline{\mathbf X}$ "
        r"$+\,\mu\,\mathcal E(\underline{\mathbf P})\mathbf K\mathbf J\mathbf J^\top\mathbf "
        r"K^\top]\geq0$, so (B.4) is convex, and its gradient is twice the residual of (3.70) "
        r"(B.5).",
    'If D embeds isometrically in a Hilbert space (the mCvMd defined by its integral, for every '
    'b_max; the L2 distance of densities; the Hellinger distance sqrt(1 - int sqrt(p1 p2))), '
    'every covariance of Table 2.1 (gamma <= 2) of Delta = D is positive semidefinite at every '
    "length scale. The thesis's closed form of the mCvMd equals the integral only as b_max -> "
    'infinity; with a finite b_max it is covered only while all points lie within about 2 b_max '
    'of each other. Proof: each covariance is a scale mixture int exp(-t Delta^2) dmu(t) (t '
    "Delta^2 for SE, Gamma mixtures for RQ and Matern, Bernstein's theorem for "
    'exp(-(Delta/l)^gamma)), and exp(-t D^2) is PSD for all t > 0 iff D^2 is conditionally '
    'negative definite, i.e. D is Hilbertian (Schoenberg); the mCvMd integral is an L2 norm of '
    'P_1 - P_2 over (m, b).':
        r"If $D$ embeds isometrically in a Hilbert space (the mCvMd defined by its integral, for "
        r"every $b_{\max}$; the $L_2$ distance of densities; the Hellinger distance "
        r"$\sqrt{1-\int\sqrt{p_1p_2}}$), every covariance of Table 2.1 ($\gamma\leq2$) of "
        r"$\Delta=D$ is positive semidefinite at every length scale. The thesis's closed form of "
        r"the mCvMd equals the integral only as $b_{\max}\to\infty$; with a finite $b_{\max}$ "
        r"it is covered only while all points lie within about $2b_{\max}$ of each other. Proof: "
        r"each covariance is a scale mixture $\int e^{-t\Delta^2}\,\mathrm d\mu(t)$ "
        r"($t\Delta^2$ for SE, Gamma mixtures for RQ and Matérn, Bernstein's theorem for "
        r"$e^{-(\Delta/l)^\gamma}$), and $e^{-tD^2}$ is PSD for all $t>0$ iff $D^2$ is "
        r"conditionally negative definite, i.e. $D$ is Hilbertian (Schoenberg); the mCvMd "
        r"integral is an $L_2$ norm of $P_1-P_2$ over $(m,b)$.",
    'If M = 1 and C = I (state feedback), H H^T > 0, (A, B) is stabilisable and Q > 0, Alg. 3.1 '
    'converges from every X_0 > 0, P_0 >= 0 to the LQ gain. Proof: H H^T > 0 keeps X_k > 0, so '
    'the X-factors cancel in (3.34), L = -(R + B^T P B)^{-1} B^T P A, and (3.35) for P is the '
    'Riccati value iteration, which converges to the stabilising solution (Kalman; Bertsekas, '
    'Vol. 1, Prop. 4.4.1); X then follows a converging Lyapunov recursion. Without H H^T > 0, '
    'X_k can become singular and (3.34) leaves L undetermined.':
        r"If $M=1$ and $\mathbf C=\mathbf I$ (state feedback), $\mathbf H\mathbf "
        r"H^\top\succ0$, $(\mathbf A,\mathbf B)$ is stabilisable and $\mathbf Q>0$, Alg. 3.1 "
        r"converges from every $\mathbf X_0>0$, $\mathbf P_0\geq0$ to the LQ gain. Proof: "
        r"$\mathbf H\mathbf H^\top\succ0$ keeps $\mathbf X_k\succ0$, so the $\mathbf "
        r"X$-factors cancel in (3.34), $\mathbf L=-(\mathbf R+\mathbf B^\top\mathbf "
        r"P\mathbf B)^{-1}\mathbf B^\top\mathbf P\mathbf A$, and (3.35) for $\mathbf P$ is "
        r"the Riccati value iteration, which converges to the stabilising solution (Kalman; "
        r"Bertsekas, Vol. 1, Prop. 4.4.1); $\mathbf X$ then follows a converging Lyapunov "
        r"recursion. Without $\mathbf H\mathbf H^\top\succ0$, $\mathbf X_k$ can become "
        r"singular and (3.34) leaves $\mathbf L$ undetermined.",
}
"""The corrected statements (plain text in the study's records) with their math in LaTeX."""

CHECKS_TEX = {
    "Random quadratic terminal cost (PSD, possibly singular weight), random reference and "
    "evaluation mixtures: the library's s_K, v_K, V_K, S_K give E{C_K} under the evaluation "
    "mixture exactly (rounding tolerance).":
        r"Random quadratic terminal cost (PSD, possibly singular weight), random reference and "
        r"evaluation mixtures: the library's $s_K$, $\mathbf v_K$, $\mathbf V_K$, $\mathbf S_K$ "
        r"give $\mathrm E\{C_K\}$ under the evaluation mixture exactly (rounding tolerance).",
    "Random linear-Gaussian system (1-2 states, inputs, outputs; horizon 2-3), quadratic costs, "
    "random reference policy and steps eps_k: the library's V_0 at a random mean against the "
    "exact expected cost of the induced policy (forward moments), and for eps_k = 1 against the "
    "Riccati/LQG optimum.":
        r"Random linear-Gaussian system (1-2 states, inputs, outputs; horizon 2-3), quadratic "
        r"costs, random reference policy and steps $\varepsilon_k$: the library's $V_0$ at a "
        r"random mean against the exact expected cost of the induced policy (forward moments), and "
        r"for $\varepsilon_k=1$ against the Riccati/LQG optimum.",
    "Random inputs in R^1-3, outputs, covariance of Table 2.1 and hyperparameters: "
    "DistributionGP's mean, variance and joint covariance against conditioning the joint Gaussian "
    "through its precision matrix (eigendecomposition), within 64 eps (M + N) cond x scale.":
        r"Random inputs in $\mathbb R^{1\dots3}$, outputs, covariance of Table 2.1 and "
        r"hyperparameters: `DistributionGP`'s mean, variance and joint covariance against "
        r"conditioning the joint Gaussian through its precision matrix (eigendecomposition), "
        r"within $64\,\varepsilon\,(M+N)\,\mathrm{cond}\times\mathrm{scale}$.",
    "Random A_i, T and S_i > 0; Q solved from each form; if Q > 0, mean-square stability decided "
    "by the dense eigenvalues of the second-moment map, its matrix built from the map's action on "
    "a basis.":
        r"Random $\mathbf A_i$, $\mathbf T$ and $\mathbf S_i>0$; $\mathbf Q$ solved from each "
        r"form; if $\mathbf Q>0$, mean-square stability decided by the dense eigenvalues of the "
        r"second-moment map, its matrix built from the map's action on a basis.",
    "Formula against the Monte Carlo stationary E{z^T z} (1000 runs), within 6 standard errors.":
        r"Formula against the Monte Carlo stationary $\mathrm E\{\mathbf z^\top\mathbf z\}$ (1000 "
        r"runs), within 6 standard errors.",
    "Y_i and G random SPD at random scales, drawn with no relation to L's Lyapunov equation; "
    "premise: the BMI (3.15) by eigenvalues; conclusion: P = D(Y) satisfies (3.14)'s constraint, "
    "L stabilises, and the objective >= ||G||_2^2 of L.":
        r"$\mathbf Y_i$ and $\mathbf G$ random SPD at random scales, drawn with no relation to "
        r"$\mathbf L$'s Lyapunov equation; premise: the BMI (3.15) by eigenvalues; conclusion: "
        r"$\mathbf P=\mathcal D(\mathbf Y)$ satisfies (3.14)'s constraint, $\mathbf L$ stabilises, "
        r"and the objective $\geq\|G\|_2^2$ of $\mathbf L$.",
    "LMIs solved (Clarabel); feasibility from the certificate (the returned matrices satisfy the "
    "LMIs by eigenvalues, margin >= -eps/2); rho of the recovered gain by the dense second-moment "
    "map. Conservatism: SOF stabilisability by a 2001-point grid over scalar L plus a bounded "
    "search.":
        r"LMIs solved (Clarabel); feasibility from the certificate (the returned matrices satisfy "
        r"the LMIs by eigenvalues, margin $\geq-\varepsilon/2$); $\rho$ of the recovered gain by "
        r"the dense second-moment map. Conservatism: SOF stabilisability by a 2001-point grid over "
        r"scalar $\mathbf L$ plus a bounded search.",
    "Formula against the Monte Carlo stationary E{z^T z}, within 6 standard errors.":
        r"Formula against the Monte Carlo stationary $\mathrm E\{\mathbf z^\top\mathbf z\}$, "
        r"within 6 standard errors.",
    "As Lemma 3.8 with mode-dependent G_i and L_i.":
        r"As Lemma 3.8 with mode-dependent $\mathbf G_i$ and $\mathbf L_i$.",
    "LMIs solved (Clarabel); feasibility from the verified certificate; rho of A_i + B_i L_i C_i "
    "by the dense second-moment map.":
        r"LMIs solved (Clarabel); feasibility from the verified certificate; $\rho$ of "
        r"$\mathbf A_i+\mathbf B_i\mathbf L_i\mathbf C_i$ by the dense second-moment map.",
    "Recursion against Monte Carlo E{x_k x_k^T 1(theta_k=i)} (10000 runs, k = 1..3, "
    "Gaussian-mixture x_0, closed loop scaled to max ||A_i + B_i L C_i|| in [0.5, 1.5]), every "
    "entry within 6 standard errors.":
        r"Recursion against Monte Carlo $\mathrm E\{\mathbf x_k\mathbf x_k^\top\mathbf "
        r"1(\theta_k=i)\}$ (10000 runs, $k=1,\dots,3$, Gaussian-mixture $\mathbf x_0$, closed loop "
        r"scaled to $\max\|\mathbf A_i+\mathbf B_i\mathbf L\mathbf C_i\|\in[0.5,1.5]$), every "
        r"entry within 6 standard errors.",
    "The printed objective (defined when n_y = n_x) against the average cost, the mean stage cost "
    "of the moment recursion from a random x_0 and theta_0 ~ mu_inf over steps h..2h-1 with rho^h "
    "<= 1e-13, within 1e-8; the reading with C_i^T L^T R_i L C_i is checked beside it.":
        r"The printed objective (defined when $n_y=n_x$) against the average cost, the mean stage "
        r"cost of the moment recursion from a random $\mathbf x_0$ and $\theta_0\sim\mu_\infty$ "
        r"over steps $h,\dots,2h-1$ with $\rho^h\leq10^{-13}$, within $10^{-8}$; the reading with "
        r"$\mathbf C_i^\top\mathbf L^\top\mathbf R_i\mathbf L\mathbf C_i$ is checked beside it.",
    "Printed formula (column-major vec) at random X, P; residual of (3.31); also compared with "
    "asoc.mjls.gain_from_moments.":
        r"Printed formula (column-major vec) at random $\mathbf X$, $\mathbf P$; residual of "
        r"(3.31); also compared with `asoc.mjls.gain_from_moments`.",
    "Premise by a 2001-point grid over scalar L plus a bounded search (rho < 1); Alg. 3.1 "
    "(asoc.mjls.static_output_feedback) must converge to a stabilising gain, the same from 1e-4 I "
    "and from I.":
        r"Premise by a 2001-point grid over scalar $\mathbf L$ plus a bounded search ($\rho<1$); "
        r"Alg. 3.1 (`asoc.mjls.static_output_feedback`) must converge to a stabilising gain, the "
        r"same from $10^{-4}\mathbf I$ and from $\mathbf I$.",
    "x~^T Q~ x~ against x^T Q x + u^T R u at random points.":
        r"$\tilde{\mathbf x}^\top\tilde{\mathbf Q}\tilde{\mathbf x}$ against "
        r"$\mathbf x^\top\mathbf Q\mathbf x+\mathbf u^\top\mathbf R\mathbf u$ at random points.",
    "Printed blocks against Monte Carlo of plant and controller (10000 runs, k = 1..3, max "
    "||A~_i|| in [0.5, 1.5]), within 6 standard errors.":
        r"Printed blocks against Monte Carlo of plant and controller (10000 runs, $k=1,\dots,3$, "
        r"$\max\|\tilde{\mathbf A}_i\|\in[0.5,1.5]$), within 6 standard errors.",
    "Stated form against the Lagrangian built densely: the augmented closed loop, its noise and "
    "cost assembled block by block, the constraint multiplied by P~ as a vector product.":
        r"Stated form against the Lagrangian built densely: the augmented closed loop, its noise "
        r"and cost assembled block by block, the constraint multiplied by $\tilde{\mathbf P}$ as a "
        r"vector product.",
    "Exact X~_inf, P~_inf of a random stabilising (F, K, L); smallest eigenvalue of bound minus "
    "matrix.":
        r"Exact $\tilde{\mathbf X}_\infty$, $\tilde{\mathbf P}_\infty$ of a random stabilising "
        r"$(\mathbf F,\mathbf K,\mathbf L)$; smallest eigenvalue of bound minus matrix.",
    "Moment form (asoc.mjls.finite_horizon_cost) against Monte Carlo of plant and time-variant "
    "controller (10000 runs), within 6 standard errors.":
        r"Moment form (`asoc.mjls.finite_horizon_cost`) against Monte Carlo of plant and "
        r"time-variant controller (10000 runs), within 6 standard errors.",
    "Exact J_0 (moment recursion) against Jbar_0 from (3.66)-(3.69), random gains, horizons 2-8.":
        r"Exact $\mathcal J_0$ (moment recursion) against $\bar{\mathcal J}_0$ from (3.66)-(3.69), "
        r"random gains, horizons 2-8.",
    "At one step, the solution of (3.70) against random perturbations of (F_k, K_k, L_k) in Jbar_k "
    "(3.65)/(3.68)-(3.69).":
        r"At one step, the solution of (3.70) against random perturbations of "
        r"$(\mathbf F_k,\mathbf K_k,\mathbf L_k)$ in $\bar{\mathcal J}_k$ (3.65)/(3.68)-(3.69).",
    "Alg. 3.3 (asoc.mjls.finite_horizon_dynamic_output_feedback, Step 5 safeguard on) from random "
    "gains: increases of Jbar_0, convergence within 300 iterations, change of the gains over 20 "
    "more iterations.":
        r"Alg. 3.3 (`asoc.mjls.finite_horizon_dynamic_output_feedback`, Step 5 safeguard on) from "
        r"random gains: increases of $\bar{\mathcal J}_0$, convergence within 300 iterations, "
        r"change of the gains over 20 more iterations.",
    'Random A_i, T and S_i > 0 (half the draws: 3 modes, 2-3 states, T near a 3-cycle, A scaled '
    "to put the premise's radius just below 1); Q solved from each form; if Q > 0, mean-square "
    'stability decided by the dense eigenvalues of the second-moment map, its matrix built from '
    "the map's action on a basis.":
        r"Random $\mathbf A_i$, $\mathbf T$ and $\mathbf S_i>0$ (half the draws: 3 modes, 2-3 "
        r"states, $\mathbf T$ near a 3-cycle, $\mathbf A$ scaled to put the premise's radius "
        r"just below 1); $\mathbf Q$ solved from each form; if $\mathbf Q>0$, mean-square "
        r"stability decided by the dense eigenvalues of the second-moment map, its matrix built "
        r"from the map's action on a basis.",
    "Half the draws: Y_i and G random SPD at random scales, with no relation to L's Lyapunov "
    "equation; half at the BMI's boundary: Y = s Acl D(Y) Acl^T + mu H H^T + delta I, G from "
    'D(Y), s on [0.5, 1.5]; premise: the BMI (3.15) by eigenvalues; conclusion: P = D(Y) '
    "satisfies (3.14)'s constraint, L stabilises, and the objective >= ||G||_2^2 of L.":
        r"Half the draws: $\mathbf Y_i$ and $\mathbf G$ random SPD at random scales, with no "
        r"relation to $\mathbf L$'s Lyapunov equation; half at the BMI's boundary: $\mathbf "
        r"Y=s\,\mathbf A_{cl}\mathcal D(\mathbf Y)\mathbf A_{cl}^\top+\mu\mathbf "
        r"H\mathbf H^\top+\delta\mathbf I$, $\mathbf G$ from $\mathcal D(\mathbf Y)$, "
        r"$s\in[0.5,1.5]$; premise: the BMI (3.15) by eigenvalues; conclusion: $\mathbf "
        r"P=\mathcal D(\mathbf Y)$ satisfies (3.14)'s constraint, $\mathbf L$ stabilises, and "
        r"the objective $\geq\|G\|_2^2$ of $\mathbf L$.",
    'As Lemma 3.8 with mode-dependent G_i = D_i(Y) (at the boundary) and L_i.':
        r"As Lemma 3.8 with mode-dependent $\mathbf G_i=\mathcal D_i(\mathbf Y)$ (at the "
        r"boundary) and $\mathbf L_i$.",
}
"""What one instance of each statement checks (plain text in ``Statement.checked``), math in
LaTeX."""
