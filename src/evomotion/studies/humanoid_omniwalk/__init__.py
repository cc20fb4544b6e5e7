"""Study ``humanoid-omniwalk``: a closed-loop omnidirectional NAO walk controller."""
