"""Study ``gym``: Gymnasium environments as policy-search problems."""
