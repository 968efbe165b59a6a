"""The test sites of the papers (one source for their constants)."""

SITE_LAT_DEG = 28.222  # deg N, latitude of seed 000's test site (also the default static base)
SITE_LAT = SITE_LAT_DEG * 3.141592653589793 / 180.0  # rad
