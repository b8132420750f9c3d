print("size report TODO")
