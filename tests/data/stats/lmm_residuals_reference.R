# Conditional residuals of linear mixed models (y - X beta - Z b, R's residuals(lmer)) and
# Shapiro-Wilk on them (shapiro.test), the normality check the report runs on the LMM
# (issue #32). REML fits with tight tolerances on data sets that ship with lme4 (the CSVs
# lmm_formula_reference.R writes) and on lmm_crossed.csv (lmm_reference.R).
# R 4.2.2, lme4 1.1.31, jsonlite 1.8.4 (Debian 12: apt-get install r-base-core r-cran-lme4
# r-cran-jsonlite). Run from this directory: Rscript lmm_residuals_reference.R
#   (writes lmm_residuals_reference.json)
suppressPackageStartupMessages({ library(lme4); library(jsonlite) })
options(contrasts = c("contr.sum", "contr.poly"))
ctrl <- lmerControl(optimizer = "nloptwrap",
                    optCtrl = list(xtol_abs = 1e-12, ftol_abs = 1e-15, xtol_rel = 0, ftol_rel = 0, maxeval = 100000))
fits <- list(
  sleepstudy = list(csv = "lmm_sleepstudy.csv", formula = "Reaction ~ Days + (Days | Subject)"),
  penicillin = list(csv = "lmm_penicillin.csv", formula = "diameter ~ 1 + (1 | plate) + (1 | sample)"),
  crossed = list(csv = "lmm_crossed.csv",
                 formula = "score ~ method * texture + (1 + method | participant) + (1 | material)"))
out <- list()
for (nm in names(fits)) {
  d <- read.csv(fits[[nm]]$csv, stringsAsFactors = TRUE)
  m <- lmer(as.formula(fits[[nm]]$formula), data = d, REML = TRUE, control = ctrl)
  r <- unname(residuals(m))
  sw <- shapiro.test(r)
  out[[nm]] <- list(csv = fits[[nm]]$csv, formula = fits[[nm]]$formula, residuals = r,
                    shapiro_W = unname(sw$statistic), shapiro_p = sw$p.value)
}
writeLines(toJSON(out, auto_unbox = TRUE, digits = NA, pretty = TRUE), "lmm_residuals_reference.json")
