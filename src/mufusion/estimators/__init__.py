"""mufusion.estimators"""
