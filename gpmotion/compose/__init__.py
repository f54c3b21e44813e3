"""Composite motions (Auslander et al. 1995, §3): the script language,
composite controllers, the transition search and robust (perturbed-start)
evaluation."""
