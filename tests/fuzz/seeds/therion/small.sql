create table STATION (ID integer, NAME varchar(7), SURVEY_ID integer, X real, Y real, Z real);
create table SHOT (ID integer, FROM_ID integer, TO_ID integer, CENTRELINE_ID integer, LENGTH real, BEARING real, GRADIENT real, ADJ_LENGTH real, ADJ_BEARING real, ADJ_GRADIENT real, ERR_LENGTH real, ERR_BEARING real, ERR_GRADIENT real);
 insert into STATION values (1, 'GH.1', 23, 739893.00, 6301812.00, 10.00);
insert into STATION values (2, '.', 23, 739893.03, 6301813.32, 12.86);
insert into STATION values (3, '.', 23, 739893.72, 6301812.26, 13.87);
insert into STATION values (4, '.', 23, 739893.96, 6301810.71, 13.70);
 insert into SHOT values (1, 1, 2, 25, 3.15, 1.10, 65.30, 3.15, 1.30, 65.22, 0.01, 50.06, -16.27);
insert into SHOT values (2, 1, 3, 25, 3.95, 70.00, 78.80, 3.94, 70.14, 78.81, 0.01, 201.67, -61.52);
insert into SHOT values (3, 1, 4, 25, 4.03, 143.10, 66.50, 4.03, 143.34, 66.51, 0.01, 224.48, 31.53);
