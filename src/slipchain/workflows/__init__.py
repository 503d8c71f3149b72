"""Whole jobs built from the layers below: the main job (reproduce Fig. 6), the mechanism on a store, figures from stores, the tester analysis."""
