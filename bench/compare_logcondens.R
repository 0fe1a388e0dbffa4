# Log-concave MLE: ident vs R's logcondens (Debian r-cran-logcondens) on the same samples,
# n = 10^3, 10^4, 10^5 standard normal draws (set.seed(7)).
# Usage (from the repository root): Rscript bench/compare_logcondens.R [path/to/ident]
# ident's time is that of the whole `ident logcondens --json` process (CSV parsing and start-up included,
# so the ratio understates the algorithm's speed); logcondens' is system.time(logConDens(...)).
# Both wall (elapsed) and CPU (user + sys; the child's for ident) times and ratios are printed.
library(logcondens)
args <- commandArgs(trailingOnly = TRUE)
ident <- if (length(args) >= 1) args[1] else "build/bin/ident"
cat(sprintf("%8s %22s %22s %12s %10s %10s %8s %10s %10s %8s %12s\n", "n", "ident loglik", "logcondens loglik",
            "rel diff", "ident [s]", "R [s]", "ratio", "ident cpu", "R cpu", "ratio", "knots i/R"))
for (n in c(1000, 10000, 100000)) {
  set.seed(7)
  x <- rnorm(n)
  file <- tempfile(fileext = ".csv")
  write.table(data.frame(x = sprintf("%.17g", x)), file, row.names = FALSE, quote = FALSE)
  ti <- system.time(out <- system2(ident, c("logcondens", file, "--json"), stdout = TRUE))
  t_ident <- ti[["elapsed"]]
  c_ident <- ti[["user.child"]] + ti[["sys.child"]]
  txt <- paste(out, collapse = " ")
  loglik <- as.numeric(sub(".*\"loglik\": *([-0-9.eE+]+).*", "\\1", txt))
  knots_json <- sub(".*\"knots\": *\\[([^]]*)\\].*", "\\1", txt)
  nk <- length(strsplit(knots_json, ",")[[1]])
  tr <- system.time(res <- logConDens(x, smoothed = FALSE, print = FALSE))
  t_r <- tr[["elapsed"]]
  c_r <- tr[["user.self"]] + tr[["sys.self"]]
  r_loglik <- n * sum(res$w * res$phi)
  cat(sprintf("%8d %22.12f %22.12f %12.3e %10.3f %10.3f %7.1fx %10.3f %10.3f %7.1fx %12s\n", n, loglik, r_loglik,
              (loglik - r_loglik) / abs(r_loglik), t_ident, t_r, t_r / t_ident, c_ident, c_r, c_r / max(c_ident, 1e-3),
              paste0(nk, "/", sum(res$IsKnot))))
  unlink(file)
}
