# Golden values for tests/density/logconcave_mle_test.cc from R's logcondens (Debian r-cran-logcondens).
# Run from this directory:  Rscript logcondens_golden.R
# Writes, per case, <name>_samples.csv (the samples, 17 digits), <name>_knots.csv (knots and log-density
# phi at the knots), <name>_cdf.csv (distinct sorted x and the fitted CDF Fhat; every 50th x when there are more than 1000), and summary.csv with
# loglik = n * sum(w * phi) = sum_i log fhat(X_i) and logcondens' own L = sum(w * phi) - int exp(phi).
library(logcondens)
cases <- list(
  list(name = "normal50", seed = 1, draw = function(n) rnorm(n), n = 50),
  list(name = "laplace100", seed = 2, draw = function(n) { u <- runif(n) - 0.5; -sign(u) * log(1 - 2 * abs(u)) }, n = 100),
  list(name = "gamma200", seed = 3, draw = function(n) rgamma(n, shape = 2), n = 200),
  list(name = "exponential500", seed = 4, draw = function(n) rexp(n), n = 500),
  list(name = "logistic1000", seed = 5, draw = function(n) rlogis(n), n = 1000),
  list(name = "normal10000", seed = 6, draw = function(n) rnorm(n), n = 10000)
)
summary <- data.frame()
for (case in cases) {
  set.seed(case$seed)
  x <- case$draw(case$n)
  write.table(data.frame(x = sprintf("%.17g", x)), paste0(case$name, "_samples.csv"), sep = ",",
              row.names = FALSE, quote = FALSE)
  res <- logConDens(x, smoothed = FALSE, print = FALSE)
  knots <- res$IsKnot == 1
  write.table(data.frame(knot = sprintf("%.17g", res$x[knots]), phi = sprintf("%.17g", res$phi[knots])),
              paste0(case$name, "_knots.csv"), sep = ",", row.names = FALSE, quote = FALSE)
  idx <- if (length(res$x) > 1000) seq(1, length(res$x), by = 50) else seq_along(res$x)  # keep files small
  write.table(data.frame(x = sprintf("%.17g", res$x[idx]), Fhat = sprintf("%.17g", res$Fhat[idx])),
              paste0(case$name, "_cdf.csv"), sep = ",", row.names = FALSE, quote = FALSE)
  summary <- rbind(summary, data.frame(name = case$name, n = case$n,
                                       loglik = sprintf("%.17g", case$n * sum(res$w * res$phi)),
                                       L = sprintf("%.17g", res$L), knots = sum(knots)))
}
write.table(summary, "summary.csv", sep = ",", row.names = FALSE, quote = FALSE)
