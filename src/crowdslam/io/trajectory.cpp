// Implementation pending (eval/trajectory helper).
