# Reference values for linear mixed models (hapticlab stats lmm): lme4::lmer fits (REML and
# ML) with lmerTest's Satterthwaite df for the coefficient t tests and the type-3 F tests
# (anova(m, type = 3) with sum-to-zero contrasts, which is what afex::mixed(method = "S")
# reports), and for the REML fits the same with Kenward-Roger df (pbkrtest 0.5.2).
# R 4.2.2, lme4 1.1.31, lmerTest 3.1.3, pbkrtest 0.5.2, jsonlite 1.8.4 (Debian 12: apt-get install
# r-base-core r-cran-lme4 r-cran-lmertest r-cran-pbkrtest r-cran-jsonlite).
# Run from this directory: Rscript lmm_reference.R   (writes lmm_*.csv and lmm_reference.json)
#
# The optimizer runs with tight tolerances (lme4's default nloptwrap/BOBYQA, xtol_abs 1e-12)
# so the stored numbers are the optimum itself, not lme4's default stopping point (which is
# within ~1e-6 of it).
suppressPackageStartupMessages({ library(lme4); library(lmerTest); library(jsonlite) })
options(contrasts = c("contr.sum", "contr.poly"))
set.seed(4711)

# crossed: 24 participants x 3 methods x 8 materials (4 rough, 4 smooth), one rating each;
# participants differ in their method effects (correlated random slopes), materials in level.
make_crossed <- function() {
  methods <- c("audio", "haptic", "visual")
  mats <- sprintf("M%d", 1:8)
  texture <- setNames(rep(c("rough", "smooth"), each = 4), mats)
  mat_eff <- setNames(rnorm(8, 0, 3), mats)
  rows <- list()
  for (p in 1:24) {
    b <- rnorm(3, 0, c(6, 3, 2))
    for (m in 1:3) for (mt in mats) {
      mu <- 50 + c(0, 4, 7)[m] + (texture[mt] == "rough") * c(2, -1, 0)[m] + b[1] + c(-1, 0, 1)[m] * b[2] +
        (m == 2) * b[3] + mat_eff[mt]
      rows[[length(rows) + 1]] <- data.frame(participant = sprintf("P%02d", p), method = methods[m],
        material = mt, texture = unname(texture[mt]), score = round(mu + rnorm(1, 0, 4), 4))
    }
  }
  do.call(rbind, rows)
}
# unbalanced: 15 participants x 2 methods x 4 speeds (numeric, m/s) x 2 repetitions, 25 %
# of the rows deleted at random (every method cell keeps data); random intercept and speed
# slope per participant.
make_unbalanced <- function() {
  rows <- list()
  for (p in 1:15) {
    b0 <- rnorm(1, 0, 5); b1 <- rnorm(1, 0, 20)
    for (m in c("tap", "slide")) for (v in c(0.05, 0.1, 0.15, 0.2)) for (r in 1:2) {
      mu <- 30 + (m == "slide") * 3 + (80 + b1) * v + b0
      rows[[length(rows) + 1]] <- data.frame(participant = sprintf("S%02d", p), method = m,
        speed_mps = v, repetition = r, score = round(mu + rnorm(1, 0, 3), 4))
    }
  }
  d <- do.call(rbind, rows)
  d[sort(sample(nrow(d), round(0.75 * nrow(d)))), ]
}
# singular: no material variance at all, so lme4 puts its theta on the boundary (0).
make_singular <- function() {
  rows <- list()
  for (p in 1:12) {
    b <- rnorm(1, 0, 4)
    for (m in c("A", "B", "C")) for (mt in sprintf("T%d", 1:5)) {
      rows[[length(rows) + 1]] <- data.frame(participant = sprintf("P%02d", p), method = m, material = mt,
        score = round(20 + (m == "B") * 2 + b + rnorm(1, 0, 3), 4))
    }
  }
  do.call(rbind, rows)
}

ctrl <- lmerControl(optimizer = "nloptwrap",
                    optCtrl = list(xtol_abs = 1e-12, ftol_abs = 1e-15, xtol_rel = 0, ftol_rel = 0, maxeval = 100000))

summarise <- function(m) {
  s <- summary(m)
  co <- s$coefficients
  fixed <- lapply(seq_len(nrow(co)), function(i) list(name = rownames(co)[i], estimate = co[i, "Estimate"],
    se = co[i, "Std. Error"], df = co[i, "df"], t = co[i, "t value"], p = co[i, "Pr(>|t|)"]))
  a <- anova(m, type = 3, ddf = "Satterthwaite")
  ftests <- lapply(seq_len(nrow(a)), function(i) list(term = rownames(a)[i], num_df = a[i, "NumDF"],
    den_df = a[i, "DenDF"], F = a[i, "F value"], p = a[i, "Pr(>F)"]))
  vc <- as.data.frame(VarCorr(m))
  random <- lapply(seq_len(nrow(vc)), function(i) list(group = vc$grp[i], var1 = vc$var1[i],
    var2 = if (is.na(vc$var2[i])) "" else vc$var2[i], vcov = vc$vcov[i], sdcor = vc$sdcor[i]))
  out <- list(theta = unname(getME(m, "theta")), sigma = sigma(m), logLik = as.numeric(logLik(m)),
       deviance = if (isREML(m)) NA else deviance(m), REMLcrit = if (isREML(m)) REMLcrit(m) else NA,
       AIC = AIC(m), singular = isSingular(m), fixed = fixed, anova = ftests, random = random)
  if (isREML(m)) {  # Kenward-Roger (pbkrtest through lmerTest): REML fits only
    ck <- summary(m, ddf = "Kenward-Roger")$coefficients
    ak <- anova(m, type = 3, ddf = "Kenward-Roger")
    out$kr <- list(
      fixed = lapply(seq_len(nrow(ck)), function(i) list(name = rownames(ck)[i], estimate = ck[i, "Estimate"],
        se = ck[i, "Std. Error"], df = ck[i, "df"], t = ck[i, "t value"], p = ck[i, "Pr(>|t|)"])),
      anova = lapply(seq_len(nrow(ak)), function(i) list(term = rownames(ak)[i], num_df = ak[i, "NumDF"],
        den_df = ak[i, "DenDF"], F = ak[i, "F value"], p = ak[i, "Pr(>F)"])))
  }
  out
}

sets <- list(
  crossed = list(data = make_crossed(),
                 formula = "score ~ method * texture + (1 + method | participant) + (1 | material)"),
  unbalanced = list(data = make_unbalanced(),
                    formula = "score ~ method * speed_mps + (1 + speed_mps | participant)"),
  singular = list(data = make_singular(),
                  formula = "score ~ method + (1 | participant) + (1 | material)"))
out <- list()
for (nm in names(sets)) {
  d <- sets[[nm]]$data
  write.csv(d, sprintf("lmm_%s.csv", nm), row.names = FALSE, quote = FALSE)
  d <- read.csv(sprintf("lmm_%s.csv", nm), stringsAsFactors = TRUE)
  f <- as.formula(sets[[nm]]$formula)
  reml <- lmerTest::lmer(f, data = d, REML = TRUE, control = ctrl)
  ml <- lmerTest::lmer(f, data = d, REML = FALSE, control = ctrl)
  out[[nm]] <- list(csv = sprintf("lmm_%s.csv", nm), formula = sets[[nm]]$formula,
                    reml = summarise(reml), ml = summarise(ml))
}
writeLines(toJSON(out, auto_unbox = TRUE, digits = NA, pretty = TRUE, na = "null"), "lmm_reference.json")
