"""Conventional Gait Model (Plug-in Gait lower body): segments, joint centres, angles."""
