# Reference fits for tests/stats/psychometric_test.cpp and tests/apps/cmd_stats_psychometric_test.cpp:
# maximum-likelihood psychometric functions fitted by R's glm (binomial family), plain and
# with psyphy's links for the guess rate. Writes ecc2.csv, ecc2_fits.csv and ecc2_links.csv.
#
# Data: psyphy's (GPL; see README.md here) `ecc2` ("4-afc Detection and Identification of Letters", Yssaad-Fesselier
# and Knoblauch 2006, doi:10.1016/j.visres.2005.11.008), the 48 rows as shipped, written to
# ecc2.csv. Regenerate with (Debian 12: r-base-core 4.2.2, r-cran-psyphy 0.2-3):
#   Rscript tests/data/psychometric/ecc2_reference.R tests/data/psychometric
# Parameterisation (docs/psychophysics.md): eta = a + b g(x), g(x) = x (logistic, normal) or
# ln x (Weibull); threshold alpha = -a/b (Weibull: exp(-a/b)), slope beta = b;
# psi = gamma + (1 - gamma - lambda) F(eta).
suppressMessages(library(psyphy))
args <- commandArgs(trailingOnly = TRUE)
out <- if (length(args) > 0) args[1] else "."
data(ecc2)
write.csv(ecc2, file.path(out, "ecc2.csv"), row.names = FALSE, quote = FALSE)

ctl <- glm.control(epsilon = 1e-14, maxit = 200)
rows <- list()
add <- function(name, task, size, shape, lapse_mode, lapse, fit) {
  a <- unname(coef(fit)[1]); b <- unname(coef(fit)[2])
  thr <- if (shape == "weibull") exp(-a / b) else -a / b
  rows[[length(rows) + 1]] <<- data.frame(name = name, task = task, size = size, shape = shape,
    guess = 0.25, lapse_mode = lapse_mode, lapse = sprintf("%.12g", lapse),
    a = sprintf("%.12g", a), b = sprintf("%.12g", b), threshold = sprintf("%.12g", thr),
    slope = sprintf("%.12g", b), loglik = sprintf("%.12g", as.numeric(logLik(fit))))
}
sub <- function(task, size) ecc2[ecc2$task == task & ecc2$Size == size, ]

# Lapse fixed at 0, guess 1/4 (mafc links).
for (size in c(12.4, 20.6)) {
  d <- sub("DET", size)
  add("det-logistic", "DET", size, "logistic", "fixed", 0,
      glm(cbind(Correct, Incorrect) ~ Contr, binomial(mafc.logit(4)), d, control = ctl))
  add("det-normal", "DET", size, "normal", "fixed", 0,
      glm(cbind(Correct, Incorrect) ~ Contr, binomial(mafc.probit(4)), d, control = ctl))
  add("det-weibull", "DET", size, "weibull", "fixed", 0,
      glm(cbind(Correct, Incorrect) ~ log(Contr), binomial(mafc.cloglog(4)), d, control = ctl))
}
# Lapse fixed at 0.02 (psyphy's 2asym links).
d <- sub("ID", 12.4)
add("id-logistic-lapse", "ID", 12.4, "logistic", "fixed", 0.02,
    glm(cbind(Correct, Incorrect) ~ Contr, binomial(logit.2asym(0.25, 0.02)), d, control = ctl))
add("id-weibull-lapse", "ID", 12.4, "weibull", "fixed", 0.02,
    glm(cbind(Correct, Incorrect) ~ log(Contr), binomial(cloglog.2asym(0.25, 0.02)), d, control = ctl))
# Lapse free in [0, 0.06]: the profile likelihood over lambda (each point a glm fit),
# maximised by optimize() to 1e-12 (psyphy's glm.WH does the same alternation to 1e-6).
for (size in c(12.4, 20.6)) {
  d <- sub("DET", size)
  prof <- function(lam) -as.numeric(logLik(glm(cbind(Correct, Incorrect) ~ Contr,
                         binomial(probit.2asym(0.25, lam)), d, control = ctl)))
  lam <- optimize(prof, c(0, 0.06), tol = 1e-12)$minimum
  add("det-normal-free", "DET", size, "normal", "free", lam,
      glm(cbind(Correct, Incorrect) ~ Contr, binomial(probit.2asym(0.25, lam)), d, control = ctl))
}
res <- do.call(rbind, rows)
write.csv(res, file.path(out, "ecc2_fits.csv"), row.names = FALSE, quote = FALSE)
print(res)

# ecc2_links.csv: every task x Size group of ecc2 under each link of `hapticlab stats
# psychometric --link` (guess 0 for logit, probit, weibull; 1/4 for the mafc links), lapse 0:
# the coefficients (intercept a, slope b of eta = a + b g(x)), their standard errors, the
# residual deviance and the log-likelihood, all to 15 significant digits.
links <- list(
  list(name = "logit", link = binomial("logit"), log_x = FALSE),
  list(name = "probit", link = binomial("probit"), log_x = FALSE),
  list(name = "weibull", link = binomial("cloglog"), log_x = TRUE),
  list(name = "mafc-logit:4", link = binomial(mafc.logit(4)), log_x = FALSE),
  list(name = "mafc-probit:4", link = binomial(mafc.probit(4)), log_x = FALSE),
  list(name = "mafc-weibull:4", link = binomial(mafc.cloglog(4)), log_x = TRUE))
g15 <- function(v) sprintf("%.15g", v)
lrows <- list()
for (task in levels(ecc2$task)) for (size in sort(unique(ecc2$Size))) {
  d <- sub(task, size)
  for (l in links) {
    f <- if (l$log_x) glm(cbind(Correct, Incorrect) ~ log(Contr), l$link, d, control = ctl)
         else glm(cbind(Correct, Incorrect) ~ Contr, l$link, d, control = ctl)
    se <- sqrt(diag(vcov(f)))
    lrows[[length(lrows) + 1]] <- data.frame(task = task, size = size, link = l$name,
      a = g15(coef(f)[1]), b = g15(coef(f)[2]), se_a = g15(se[1]), se_b = g15(se[2]),
      deviance = g15(deviance(f)), df_residual = df.residual(f),
      loglik = g15(as.numeric(logLik(f))), iterations = f$iter)
  }
}
lres <- do.call(rbind, lrows)
write.csv(lres, file.path(out, "ecc2_links.csv"), row.names = FALSE, quote = FALSE)
print(lres)
