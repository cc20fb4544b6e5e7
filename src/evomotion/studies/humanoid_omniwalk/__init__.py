"""Study ``humanoid-walk`` (once ``humanoid-omniwalk``): a closed-loop omnidirectional NAO
walk controller."""
