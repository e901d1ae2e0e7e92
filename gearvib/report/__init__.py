"""Order-analysis reports (HTML and PDF) built from run-up Datasets."""
