"""mufusion.metrics"""
