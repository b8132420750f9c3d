print("stack TODO")
