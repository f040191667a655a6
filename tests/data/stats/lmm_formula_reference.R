# Reference values for lme4's formula language in hapticlab stats lmm (issue #32 item 4): each
# feature fitted by lme4::lmer (REML) on a real data set that ships with lme4, with lmerTest's
# Satterthwaite df: fixed effects, SE, df, t, p, type 3 F tests, lme4's theta, the variance components
# (as.data.frame(VarCorr)), sigma and the REML logLik.
# Kenward-Roger SEs and df of the coefficients (pbkrtest 0.5.2) too.
# R 4.2.2, lme4 1.1.31, lmerTest 3.1.3, pbkrtest 0.5.2, jsonlite 1.8.4 (Debian 12: apt-get install r-base-core
# r-cran-lme4 r-cran-lmertest r-cran-pbkrtest r-cran-jsonlite).
# Run from this directory: Rscript lmm_formula_reference.R
#   (writes lmm_sleepstudy.csv, lmm_pastes.csv, lmm_cake.csv, lmm_penicillin.csv and
#   lmm_formula_reference.json)
# Data: sleepstudy (Belenky et al. 2003), Pastes and Penicillin (Davies & Goldsmith 1972),
# cake (Cook 1938), as lme4 ships them. The fits read the CSVs back, as hapticlab does: cake's
# replicate (1..15) is a grouping factor; temp is cake's baking temperature in degC (numeric).
suppressPackageStartupMessages({ library(lme4); library(lmerTest); library(jsonlite) })
options(contrasts = c("contr.sum", "contr.poly"))

ctrl <- lmerControl(optimizer = "nloptwrap",
                    optCtrl = list(xtol_abs = 1e-12, ftol_abs = 1e-15, xtol_rel = 0, ftol_rel = 0, maxeval = 100000))

summarise <- function(m) {
  co <- summary(m)$coefficients
  fixed <- lapply(seq_len(nrow(co)), function(i) list(name = rownames(co)[i], estimate = co[i, "Estimate"],
    se = co[i, "Std. Error"], df = co[i, "df"], t = co[i, "t value"], p = co[i, "Pr(>|t|)"]))
  a <- anova(m, type = 3, ddf = "Satterthwaite")
  ftests <- lapply(seq_len(nrow(a)), function(i) list(term = rownames(a)[i], num_df = a[i, "NumDF"],
    den_df = a[i, "DenDF"], F = a[i, "F value"], p = a[i, "Pr(>F)"]))
  vc <- as.data.frame(VarCorr(m))
  random <- lapply(seq_len(nrow(vc)), function(i) list(group = vc$grp[i], var1 = if (is.na(vc$var1[i])) "" else vc$var1[i],
    var2 = if (is.na(vc$var2[i])) "" else vc$var2[i], vcov = vc$vcov[i], sdcor = vc$sdcor[i]))
  ck <- summary(m, ddf = "Kenward-Roger")$coefficients  # pbkrtest through lmerTest
  kr <- lapply(seq_len(nrow(ck)), function(i) list(name = rownames(ck)[i], se = ck[i, "Std. Error"],
    df = ck[i, "df"]))
  list(theta = I(unname(getME(m, "theta"))), kr = kr, sigma = sigma(m), logLik = as.numeric(logLik(m)),
       REMLcrit = REMLcrit(m), singular = isSingular(m), fixed = fixed, anova = ftests, random = random)
}

data_sets <- list(sleepstudy = sleepstudy[, c("Subject", "Days", "Reaction")],
                  pastes = Pastes[, c("batch", "cask", "strength")],
                  cake = cake[, c("recipe", "replicate", "temp", "angle")],
                  penicillin = Penicillin[, c("plate", "sample", "diameter")])
for (nm in names(data_sets))
  write.csv(data_sets[[nm]], sprintf("lmm_%s.csv", nm), row.names = FALSE, quote = FALSE)

fits <- list(
  uncorrelated = list(data = "sleepstudy", formula = "Reaction ~ Days + (Days || Subject)"),
  uncorrelated_two = list(data = "sleepstudy", formula = "Reaction ~ Days + (1 + Days + I(Days^2) || Subject)"),
  nested = list(data = "pastes", formula = "strength ~ 1 + (1 | batch/cask)"),
  interaction_group = list(data = "cake", formula = "angle ~ recipe * temp + (1 | recipe:replicate)"),
  log_response = list(data = "sleepstudy", formula = "log(Reaction) ~ Days + I(Days^2) + (Days | Subject)"),
  functions = list(data = "sleepstudy", formula = "sqrt(Reaction) ~ scale(Days) + exp(Days/10) + (1 | Subject)"),
  log_crossed = list(data = "penicillin", formula = "log(diameter) ~ 1 + (1 | plate) + (1 | sample)"),
  i_arithmetic = list(data = "sleepstudy", formula = "I(Reaction/1000) ~ I((Days - 4.5)*2) + I(-Days^2/10 + 1) + (1 | Subject)"),
  no_intercept = list(data = "cake", formula = "angle ~ 0 + recipe + temp + (1 | replicate)"),
  minus_one = list(data = "sleepstudy", formula = "Reaction ~ Days - 1 + (Days | Subject)"),
  poly = list(data = "sleepstudy", formula = "Reaction ~ poly(Days, 3) + (Days | Subject)"),
  poly_interaction = list(data = "cake", formula = "angle ~ recipe * poly(temp, 2) + (1 | recipe:replicate)"))
out <- list()
for (nm in names(fits)) {
  csv <- sprintf("lmm_%s.csv", fits[[nm]]$data)
  d <- read.csv(csv, stringsAsFactors = TRUE)
  if (fits[[nm]]$data == "cake") d$replicate <- factor(d$replicate)
  m <- lmerTest::lmer(as.formula(fits[[nm]]$formula), data = d, REML = TRUE, control = ctrl)
  out[[nm]] <- list(csv = csv, formula = fits[[nm]]$formula, reml = summarise(m))
}
writeLines(toJSON(out, auto_unbox = TRUE, digits = NA, pretty = TRUE, na = "null"), "lmm_formula_reference.json")
