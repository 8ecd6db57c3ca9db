"""Third-party code kept as published, each folder with its licence and a README saying where
it comes from and what was changed."""
