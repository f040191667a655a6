# The R side of bench/stats_call_bench.cpp: what `hapticlab-stats rm-anova` + `tukey` compute
# on one criterion of tests/data/stats/example_raw.csv, as an analyst runs it in R.
# Usage: Rscript bench/stats_call.R FILE.csv
suppressPackageStartupMessages({ library(afex); library(emmeans) })
d <- subset(read.csv(commandArgs(TRUE)[1]), criterion == "realism")
a <- aov_ez("subject", "score", d, within = c("method", "material"), fun_aggregate = mean,
            include_aov = TRUE)  # emmeans model = "univariate" needs the aov fit
print(anova(a, es = "pes", correction = "GG"))
print(pairs(emmeans(a, ~method, model = "univariate"), adjust = "tukey"))
