"""Figures: functions that take Datasets (or tables) and only draw, writing PNG and PDF: the paper's, the mechanism's, the tester's."""
