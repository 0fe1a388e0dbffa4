# Reference values for ident's batch robust regressions (ident/regression/batch_regression.h, tests/regression/batch_regression_test.cc):
# MASS::rlm (Huber M, k = 1.345, MAD scale, LS start) at its defaults (acc = 1e-4, maxit = 20) and converged
# tightly (acc = 1e-13, maxit = 1000), with summary.rlm's standard errors, and the Cauchy maximum likelihood in
# (beta, gamma) jointly, NLL = sum log(gamma^2 + r^2) - n log gamma + n log pi, minimised by optim (BFGS on
# (beta, log gamma)) from the LS start, from every elemental subset (all of them for p = 2, 2000 random ones
# otherwise) and from the LTS fit, the best polished by Nelder-Mead and BFGS again.
# Records: datasets/stackloss.csv, stars_cyg.csv, telef.csv; response ~ intercept + the regressors in column
# order (the first column of stackloss, obs, and of stars_cyg, star, are row numbers and not used).
# Usage (from the repository root): Rscript bench/compare_batch_robust.R   (about a minute; MASS, robustbase)
library(MASS)
suppressWarnings(suppressMessages(library(robustbase)))
options(digits = 10)

records <- list(
  stackloss = list(file = "datasets/stackloss.csv", x = c("air_flow", "water_temp", "acid_conc"), y = "stack_loss"),
  starsCYG = list(file = "datasets/stars_cyg.csv", x = "log_Te", y = "log_light"),
  telef = list(file = "datasets/telef.csv", x = "year", y = "calls"))

cauchy_nll <- function(par, X, y) {
  p <- ncol(X)
  r <- y - X %*% par[1:p]
  g <- exp(par[p + 1])
  sum(log(g^2 + r^2)) - length(y) * log(g) + length(y) * log(pi)
}
cauchy_fit <- function(start, X, y) {
  r <- y - X %*% start
  par <- c(start, log(max(median(abs(r)), 1e-8)))
  fit <- optim(par, cauchy_nll, X = X, y = y, method = "BFGS", control = list(maxit = 1000, reltol = 1e-14))
  fit <- optim(fit$par, cauchy_nll, X = X, y = y, method = "Nelder-Mead", control = list(maxit = 5000, reltol = 1e-15))
  optim(fit$par, cauchy_nll, X = X, y = y, method = "BFGS", control = list(maxit = 1000, reltol = 1e-15))
}

set.seed(1)
for (name in names(records)) {
  rec <- records[[name]]
  d <- read.csv(rec$file)
  X <- cbind(1, as.matrix(d[, rec$x, drop = FALSE]))
  y <- d[[rec$y]]
  n <- nrow(X); p <- ncol(X)
  cat(sprintf("== %s (n = %d, p = %d)\n", name, n, p))

  for (acc in c(1e-4, 1e-13)) {
    fit <- rlm(X, y, psi = psi.huber, k = 1.345, scale.est = "MAD", init = "ls", acc = acc,
               maxit = if (acc < 1e-10) 1000 else 20)
    s <- summary(fit)
    cat(sprintf("rlm acc = %g: converged = %s, iterations = %d\n", acc, fit$converged, length(fit$conv)))
    cat("  coef  ", sprintf("%.10g", coef(fit)), "\n")
    cat("  se    ", sprintf("%.10g", s$coefficients[, 2]), "\n")
    cat("  scale ", sprintf("%.10g", fit$s), "\n")
    if (acc < 1e-10) tight <- coef(fit) else loose <- coef(fit)
  }
  cat(sprintf("  max relative difference default vs tight: %.3g\n", max(abs(loose - tight) / abs(tight))))
  # The rlm iterates on the way (tolerance 0): the task's telef reference (-398.12, 0.20414) is the 33rd.
  it33 <- suppressWarnings(rlm(X, y, psi = psi.huber, k = 1.345, scale.est = "MAD", init = "ls", acc = 0, maxit = 33))
  cat("  33rd iterate ", sprintf("%.10g", coef(it33)), "\n")

  starts <- list(qr.solve(X, y), coef(ltsReg(X[, -1, drop = FALSE], y)))
  if (p == 2) {
    pairs <- combn(n, 2)
    subsets <- lapply(seq_len(ncol(pairs)), function(j) pairs[, j])
  } else {
    subsets <- lapply(1:2000, function(j) sample(n, p))
  }
  for (idx in subsets) {
    Xs <- X[idx, , drop = FALSE]
    if (abs(det(Xs)) > 1e-10) starts[[length(starts) + 1]] <- solve(Xs, y[idx])
  }
  fits <- lapply(starts, function(b) cauchy_fit(b, X, y))
  values <- sapply(fits, function(f) f$value)
  best <- fits[[which.min(values)]]
  ls_fit <- fits[[1]]
  cat(sprintf("cauchy ML (%d starts): NLL = %.10g\n", length(starts), best$value))
  cat("  coef  ", sprintf("%.10g", best$par[1:p]), "\n")
  cat("  gamma ", sprintf("%.10g", exp(best$par[p + 1])), "\n")
  cat(sprintf("  from the LS start alone: NLL = %.10g, coef %s, gamma %.10g\n", ls_fit$value,
              paste(sprintf("%.10g", ls_fit$par[1:p]), collapse = " "), exp(ls_fit$par[p + 1])))
}
