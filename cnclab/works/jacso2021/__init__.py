"""Jacsó (2021) PhD booklet: constant-engagement 2.5D pocket tool paths — claim recipes."""
