# Kenward-Roger on a data set larger than a dense n x n computation handles comfortably
# (issue #32): afex's fhch2010 (Freeman, Heathcote, Chalmers & Hockley 2010), the naming task
# (5864 trials of 45 participants on 600 items), log RT with crossed random effects:
#   log_rt ~ stimulus * frequency + (stimulus | id) + (1 | item)
# REML fit by lme4 with tight tolerances, Kenward-Roger SEs, df and type 3 F (pbkrtest 0.5.2
# through lmerTest 3.1.3), and Satterthwaite's for comparison.
# R 4.2.2, lme4 1.1.31, lmerTest 3.1.3, pbkrtest 0.5.2, afex 1.2.1, jsonlite 1.8.4 (Debian 12:
# apt-get install r-base-core r-cran-afex r-cran-lmertest r-cran-pbkrtest r-cran-jsonlite).
# Run from this directory: Rscript lmm_kr_large_reference.R
#   (writes lmm_fhch2010_naming.csv and lmm_kr_large_reference.json; pbkrtest's dense n x n
#   computation takes minutes and a few GB here)
suppressPackageStartupMessages({ library(lme4); library(lmerTest); library(jsonlite); library(afex) })
options(contrasts = c("contr.sum", "contr.poly"))
data(fhch2010)
d <- droplevels(fhch2010[fhch2010$task == "naming", c("id", "item", "stimulus", "frequency", "log_rt")])
write.csv(d, "lmm_fhch2010_naming.csv", row.names = FALSE, quote = FALSE)
d <- read.csv("lmm_fhch2010_naming.csv", stringsAsFactors = TRUE)
formula <- "log_rt ~ stimulus * frequency + (stimulus | id) + (1 | item)"
ctrl <- lmerControl(optimizer = "nloptwrap",
                    optCtrl = list(xtol_abs = 1e-12, ftol_abs = 1e-15, xtol_rel = 0, ftol_rel = 0, maxeval = 100000))
m <- lmerTest::lmer(as.formula(formula), data = d, REML = TRUE, control = ctrl)
rows <- function(co) lapply(seq_len(nrow(co)), function(i) list(name = rownames(co)[i],
  estimate = co[i, "Estimate"], se = co[i, "Std. Error"], df = co[i, "df"], t = co[i, "t value"],
  p = co[i, "Pr(>|t|)"]))
ftab <- function(a) lapply(seq_len(nrow(a)), function(i) list(term = rownames(a)[i],
  num_df = a[i, "NumDF"], den_df = a[i, "DenDF"], F = a[i, "F value"], p = a[i, "Pr(>F)"]))
t0 <- proc.time()[["elapsed"]]
ck <- summary(m, ddf = "Kenward-Roger")$coefficients
ak <- anova(m, type = 3, ddf = "Kenward-Roger")
kr_seconds <- proc.time()[["elapsed"]] - t0
out <- list(fhch2010_naming = list(csv = "lmm_fhch2010_naming.csv", formula = formula,
  n = nrow(d), theta = I(unname(getME(m, "theta"))), sigma = sigma(m), REMLcrit = REMLcrit(m),
  reml = list(fixed = rows(summary(m)$coefficients), anova = ftab(anova(m, type = 3)),
              kr = list(fixed = rows(ck), anova = ftab(ak))),
  pbkrtest_seconds = kr_seconds))
writeLines(toJSON(out, auto_unbox = TRUE, digits = NA, pretty = TRUE, na = "null"), "lmm_kr_large_reference.json")
