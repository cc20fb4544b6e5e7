"""Study ``humanoid-balance``: a policy that keeps a pushed biped standing."""
