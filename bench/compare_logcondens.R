# Log-concave MLE: ident vs R's logcondens (Debian r-cran-logcondens) on the same samples,
# n = 10^3 ... 10^6 standard normal and standard Laplace draws (set.seed(7); Laplace = rexp(n) - rexp(n)).
# Usage (from the repository root): Rscript bench/compare_logcondens.R [path/to/ident] [--json FILE] [--max-n N]
# Times: logcondens' is system.time(logConDens(...)); ident's whole `ident logcondens --json` process (CSV
# parsing and start-up included, so that ratio understates the algorithm's speed), and the CPU time of the
# fit alone (the JSON key fit_cpu_seconds): "fit ratio" = logcondens CPU / ident fit CPU, both the
# algorithm without I/O. Printed, and with --json written as one JSON object (bench/run-baselines logcondens_vs_r).
library(logcondens)
args <- commandArgs(trailingOnly = TRUE)
json_file <- NULL
max_n <- 1e6
positional <- character(0)
i <- 1
while (i <= length(args)) {
  if (args[i] == "--json") {
    json_file <- args[i + 1]
    i <- i + 2
  } else if (args[i] == "--max-n") {
    max_n <- as.numeric(args[i + 1])
    i <- i + 2
  } else {
    positional <- c(positional, args[i])
    i <- i + 1
  }
}
ident <- if (length(positional) >= 1) positional[1] else "build/bin/ident"
cat(sprintf("%8s %8s %22s %22s %12s %10s %10s %8s %10s %10s %8s %12s %10s %10s\n", "sample", "n", "ident loglik",
            "logcondens loglik", "rel diff", "ident [s]", "R [s]", "ratio", "ident cpu", "R cpu", "ratio", "knots i/R",
            "fit cpu", "fit ratio"))
rows <- character(0)
for (dist in c("gaussian", "laplace")) {
  for (n in c(1000, 10000, 100000, 1000000)) {
    if (n > max_n) next
    set.seed(7)
    x <- if (dist == "gaussian") rnorm(n) else rexp(n) - rexp(n)
    file <- tempfile(fileext = ".csv")
    write.table(data.frame(x = sprintf("%.17g", x)), file, row.names = FALSE, quote = FALSE)
    ti <- system.time(out <- system2(ident, c("logcondens", file, "--json"), stdout = TRUE))
    t_ident <- ti[["elapsed"]]
    c_ident <- ti[["user.child"]] + ti[["sys.child"]]
    txt <- paste(out, collapse = " ")
    loglik <- as.numeric(sub(".*\"loglik\": *([-0-9.eE+]+).*", "\\1", txt))
    iterations <- as.numeric(sub(".*\"iterations\": *([0-9]+).*", "\\1", txt))
    fit_cpu <- as.numeric(sub(".*\"fit_cpu_seconds\": *([-0-9.eE+]+).*", "\\1", txt))
    knots_json <- sub(".*\"knots\": *\\[([^]]*)\\].*", "\\1", txt)
    nk <- length(strsplit(knots_json, ",")[[1]])
    tr <- system.time(res <- logConDens(x, smoothed = FALSE, print = FALSE))
    t_r <- tr[["elapsed"]]
    c_r <- tr[["user.self"]] + tr[["sys.self"]]
    r_loglik <- n * sum(res$w * res$phi)
    cat(sprintf("%8s %8d %22.12f %22.12f %12.3e %10.3f %10.3f %7.1fx %10.3f %10.3f %7.1fx %12s %10.4f %9.1fx\n", dist,
                n, loglik, r_loglik, (loglik - r_loglik) / abs(r_loglik), t_ident, t_r, t_r / t_ident, c_ident, c_r,
                c_r / max(c_ident, 1e-3), paste0(nk, "/", sum(res$IsKnot)), fit_cpu, c_r / max(fit_cpu, 1e-6)))
    rows <- c(rows, sprintf(paste0(
      "{\"sample\": \"%s\", \"n\": %d, \"ident_loglik\": %.12f, \"logcondens_loglik\": %.12f, ",
      "\"loglik_difference\": %.6e, \"ident_wall_s\": %.4f, \"logcondens_wall_s\": %.4f, \"wall_ratio\": %.2f, ",
      "\"ident_cpu_s\": %.4f, \"logcondens_cpu_s\": %.4f, \"cpu_ratio\": %.2f, \"ident_knots\": %d, ",
      "\"logcondens_knots\": %d, \"ident_iterations\": %d, \"ident_fit_cpu_s\": %.5f, \"fit_cpu_ratio\": %.2f}"),
      dist, n, loglik, r_loglik, loglik - r_loglik, t_ident, t_r, t_r / t_ident, c_ident, c_r,
      c_r / max(c_ident, 1e-3), nk, sum(res$IsKnot), iterations, fit_cpu, c_r / max(fit_cpu, 1e-6)))
    unlink(file)
  }
}
if (!is.null(json_file)) {
  writeLines(c("{\"rows\": [", paste(rows, collapse = ",\n"), "]}"), json_file)
}
