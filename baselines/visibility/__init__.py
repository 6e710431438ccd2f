"""Nilles et al. (IJRR 2021): the boundary partition P', the bounce visibility graph and safe
actions (`partition`, `graph`), and the dynamics of bounce sequences — transition maps,
contraction, limit cycles (`dynamics`)."""
