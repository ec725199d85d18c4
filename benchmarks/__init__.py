"""Monte-Carlo harness, the paper's reproduction, plots, performance measurements."""
