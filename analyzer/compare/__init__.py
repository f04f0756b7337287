"""Two recordings' judgements side by side: did the gimbal behave the same?"""
