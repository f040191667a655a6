# Reference values for the normality check on the rmANOVA's residuals (issue #32): afex's
# residuals() of an aov_ez fit (the residuals of its multivariate lm: each subject's cell
# mean minus the mean of that cell in the subject's between group) and shapiro.test() on
# them, for two real data sets shipped with afex: md_12.1 (Maxwell & Delaney, 10 subjects x
# angle (3) x noise (2), within only) and obk.long (O'Brien & Kaiser 1985, 16 subjects,
# treatment (3) x gender (2) between, phase (3) x hour (5) within).
# R 4.2.2, afex 1.2.1, jsonlite (Debian 12: apt-get install r-base-core r-cran-afex).
# Run from this directory: Rscript residuals_reference.R
# (writes md_12_1.csv, obk_long.csv and residuals_reference.json)
suppressPackageStartupMessages({ library(afex); library(jsonlite) })
data(md_12.1); data(obk.long)
write.csv(md_12.1[, c("id", "angle", "noise", "rt")], "md_12_1.csv", row.names = FALSE, quote = FALSE)
write.csv(obk.long[, c("id", "treatment", "gender", "phase", "hour", "value")], "obk_long.csv",
          row.names = FALSE, quote = FALSE)
one <- function(fit, keys) {
  r <- residuals(fit, append = TRUE)       # the fitted (cell mean) data with .residuals
  s <- shapiro.test(r$.residuals)
  rows <- r[, keys]
  rows[] <- lapply(rows, as.character)
  rows$residual <- r$.residuals
  list(n = nrow(r), W = unname(s$statistic), p = s$p.value, residuals = rows)
}
md <- aov_ez("id", "rt", md_12.1, within = c("angle", "noise"))
obk <- aov_ez("id", "value", obk.long, between = c("treatment", "gender"), within = c("phase", "hour"))
out <- list(md_12_1 = one(md, c("id", "angle", "noise")),
            obk_long = one(obk, c("id", "phase", "hour")))
writeLines(toJSON(out, digits = NA, auto_unbox = TRUE, pretty = TRUE), "residuals_reference.json")
