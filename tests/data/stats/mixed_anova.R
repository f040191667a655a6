# Reference values for mixed (between x within) ANOVA: afex::aov_ez type-3 sums of squares,
# sphericity for the within terms, emmeans Tukey comparisons.
# R 4.2.2, afex 1.2.1, car 3.1.1, emmeans 1.8.4.1, jsonlite 1.8.4 (Debian 12 packages:
# apt-get install r-base-core r-cran-afex r-cran-emmeans r-cran-jsonlite).
# Run from this directory: Rscript mixed_anova.R   (writes mixed_*.csv and mixed_anova.json)
suppressPackageStartupMessages({ library(afex); library(emmeans); library(jsonlite) })
afex_options(emmeans_model = "multivariate")
set.seed(2024)

# A: 2 groups (7 novices, 9 experts) x 3 methods, 2 repetitions per cell; S17 misses a cell
# (dropped by afex and by hapticlab). Subject-specific method slopes make it non-spherical.
make_a <- function() {
  rows <- list()
  for (s in 1:17) {
    id <- sprintf("S%02d", s)
    g <- if (s <= 7) "novice" else "expert"
    base <- rnorm(1, 50, 8)
    slope <- rnorm(1, 0, 6)
    for (m in 1:3) {
      if (s == 17 && m == 3) next
      mu <- base + c(0, 4, 7)[m] + (g == "expert") * c(0, 3, -2)[m] + (m - 2) * slope
      for (r in 1:2) rows[[length(rows) + 1]] <- data.frame(subject = id, group = g,
        method = c("haptic", "audio", "visual")[m], repetition = r, score = round(mu + rnorm(1, 0, 5), 3))
    }
  }
  do.call(rbind, rows)
}
# B: 2 groups x 2 labs (unbalanced: 4, 5, 6, 3 subjects) x method (3) x material (2).
make_b <- function() {
  rows <- list()
  sizes <- c(4, 5, 6, 3)
  s <- 0
  for (cell in 1:4) {
    g <- c("novice", "novice", "expert", "expert")[cell]
    lab <- c("lab1", "lab2", "lab1", "lab2")[cell]
    for (i in seq_len(sizes[cell])) {
      s <- s + 1
      base <- rnorm(1, 50, 8) + (lab == "lab2") * 3
      slope <- rnorm(1, 0, 4)
      for (m in 1:3) for (t in 1:2) {
        mu <- base + c(0, 3, 5)[m] + c(0, 2)[t] + (g == "expert") * (m - 2) * 2 + (m - 2) * slope +
          (lab == "lab2") * (t - 1.5) * 3
        rows[[length(rows) + 1]] <- data.frame(subject = sprintf("P%02d", s), group = g, lab = lab,
          method = c("m1", "m2", "m3")[m], material = c("wood", "foam")[t], score = round(mu + rnorm(1, 0, 4), 3))
      }
    }
  }
  do.call(rbind, rows)
}
a_data <- make_a()
b_data <- make_b()
write.csv(a_data, "mixed_2x3.csv", row.names = FALSE, quote = FALSE)
write.csv(b_data, "mixed_2x2x3x2.csv", row.names = FALSE, quote = FALSE)

anova_table <- function(fit) {
  s <- summary(fit)
  u <- as.data.frame(unclass(s$univariate.tests))
  u <- u[rownames(u) != "(Intercept)", ]
  out <- data.frame(effect = rownames(u), SS = u[["Sum Sq"]], df1 = u[["num Df"]], SS_error = u[["Error SS"]],
                    df2 = u[["den Df"]], F = u[["F value"]], p = u[["Pr(>F)"]])
  out$pes <- out$SS / (out$SS + out$SS_error)
  sp <- as.data.frame(unclass(s$sphericity.tests))
  pa <- as.data.frame(unclass(s$pval.adjustments))
  out$mauchly_W <- NA; out$mauchly_p <- NA; out$gg_epsilon <- NA; out$p_gg <- NA; out$hf_epsilon <- NA; out$p_hf <- NA
  for (e in rownames(sp)) {
    i <- which(out$effect == e)
    out$mauchly_W[i] <- sp[e, "Test statistic"]; out$mauchly_p[i] <- sp[e, "p-value"]
  }
  for (e in rownames(pa)) {
    i <- which(out$effect == e)
    out$gg_epsilon[i] <- pa[e, "GG eps"]; out$p_gg[i] <- pa[e, "Pr(>F[GG])"]
    out$hf_epsilon[i] <- pa[e, "HF eps"]; out$p_hf[i] <- pa[e, "Pr(>F[HF])"]
  }
  out
}
pairs_table <- function(fit, spec, model) {
  p <- as.data.frame(pairs(emmeans(fit, spec, model = model), adjust = "tukey"))
  data.frame(contrast = as.character(p$contrast), estimate = p$estimate, SE = p$SE, df = p$df,
             t = p$t.ratio, p = p$p.value)
}

fa <- suppressWarnings(aov_ez("subject", "score", a_data, between = "group", within = "method",
                              fun_aggregate = mean, type = 3, include_aov = TRUE))
fb <- aov_ez("subject", "score", b_data, between = c("group", "lab"), within = c("method", "material"),
             fun_aggregate = mean, type = 3)
res <- list(
  versions = list(R = as.character(getRversion()), afex = as.character(packageVersion("afex")),
                  car = as.character(packageVersion("car")), emmeans = as.character(packageVersion("emmeans"))),
  a = list(call = "aov_ez('subject', 'score', d, between = 'group', within = 'method', fun_aggregate = mean, type = 3)",
           n_kept = nrow(fa$data$wide), dropped = setdiff(unique(a_data$subject), as.character(fa$data$wide$subject)),
           anova = anova_table(fa),
           tukey_group = pairs_table(fa, ~group, "multivariate"),
           tukey_method_multivariate = pairs_table(fa, ~method, "multivariate"),
           tukey_method_univariate = pairs_table(fa, ~method, "univariate")),
  b = list(call = "aov_ez('subject', 'score', d, between = c('group', 'lab'), within = c('method', 'material'), fun_aggregate = mean, type = 3)",
           n_kept = nrow(fb$data$wide), anova = anova_table(fb),
           tukey_group = pairs_table(fb, ~group, "multivariate"),
           tukey_method_multivariate = pairs_table(fb, ~method, "multivariate"))
)
writeLines(toJSON(res, digits = NA, auto_unbox = TRUE, pretty = TRUE, na = "null"), "mixed_anova.json")
