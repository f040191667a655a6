# Reference values for the multi-site LMM (issue #35 item 4; stats/multisite.hpp): lme4::lmer
# (REML, lmerTest's Satterthwaite df) of the site model on ratings that HapticLab recorded at two
# simulated sites and merged with `hapticlab db merge`, then exported with `hapticlab export`:
#   lmm_sites_ratings.csv   the merged database's ratings.csv (written by the commands in
#                           tests/data/stats/README.md, "lmm_sites")
# This script keeps the main phase's "overall" ratings, takes each participant's site from its
# site-qualified code ("S1:P01" -> S1), writes lmm_sites.csv (site, participant, method,
# material, score) and fits
#   score ~ method * material + (1 | site) + (1 + method | site:participant)
# with contr.sum; also lmerTest::contest1D of Hybrid - FF (the method effect of the report).
# R 4.2.2, lme4 1.1.31, lmerTest 3.1.3, jsonlite 1.8.4 (Debian 12 packages).
# Run from this directory: Rscript lmm_sites_reference.R   (writes lmm_sites.csv and
# lmm_sites_reference.json)
suppressPackageStartupMessages({ library(lme4); library(lmerTest); library(jsonlite) })
options(contrasts = c("contr.sum", "contr.poly"))
ctrl <- lmerControl(optimizer = "nloptwrap",
                    optCtrl = list(xtol_abs = 1e-12, ftol_abs = 1e-15, xtol_rel = 0, ftol_rel = 0, maxeval = 100000))

r <- read.csv("lmm_sites_ratings.csv", stringsAsFactors = FALSE)
r <- r[r$phase == "main" & r$criterion == "overall", ]
d <- data.frame(site = sub(":.*$", "", r$participant), participant = r$participant,
                method = r$method, material = r$material, score = r$score)
write.csv(d, "lmm_sites.csv", row.names = FALSE, quote = FALSE)
d <- read.csv("lmm_sites.csv", stringsAsFactors = TRUE)  # read back, as hapticlab does

formula <- "score ~ method * material + (1 | site) + (1 + method | site:participant)"
m <- lmerTest::lmer(as.formula(formula), data = d, REML = TRUE, control = ctrl)
co <- summary(m)$coefficients
fixed <- lapply(seq_len(nrow(co)), function(i) list(name = rownames(co)[i], estimate = co[i, "Estimate"],
  se = co[i, "Std. Error"], df = co[i, "df"], t = co[i, "t value"], p = co[i, "Pr(>|t|)"]))
a <- anova(m, type = 3, ddf = "Satterthwaite")
ftests <- lapply(seq_len(nrow(a)), function(i) list(term = rownames(a)[i], num_df = a[i, "NumDF"],
  den_df = a[i, "DenDF"], F = a[i, "F value"], p = a[i, "Pr(>F)"]))
vc <- as.data.frame(VarCorr(m))
random <- lapply(seq_len(nrow(vc)), function(i) list(group = vc$grp[i], var1 = if (is.na(vc$var1[i])) "" else vc$var1[i],
  var2 = if (is.na(vc$var2[i])) "" else vc$var2[i], vcov = vc$vcov[i], sdcor = vc$sdcor[i]))
# Hybrid - FF: method levels sorted (FF, Hybrid), contr.sum: FF = b0 + method1, Hybrid = b0 - method1.
L <- setNames(rep(0, nrow(co)), rownames(co)); L["method1"] <- -2
ct <- contest1D(m, L)
out <- list(csv = "lmm_sites.csv", formula = formula,
            reml = list(theta = I(unname(getME(m, "theta"))), sigma = sigma(m), logLik = as.numeric(logLik(m)),
                        REMLcrit = REMLcrit(m), singular = isSingular(m), fixed = fixed, anova = ftests, random = random,
                        contrast = list(name = "Hybrid - FF", estimate = ct$Estimate, se = ct$`Std. Error`,
                                        df = ct$df, t = ct$`t value`, p = ct$`Pr(>|t|)`)))
writeLines(toJSON(out, auto_unbox = TRUE, digits = NA, pretty = TRUE, na = "null"), "lmm_sites_reference.json")
